"""``make demo``: fold every example pattern, write the folded meshes to ``out/``, render pictures into ``docs/img/``.

For each ``examples/*.svg`` (the project's own crease patterns, see ``examples/make_examples.py``):

1. ``python -m curved_fold fold <svg> --out out/<name>.fold --report out/<name>.json`` (folded FOLD file + figures);
2. ``python -m curved_fold fold <svg> --out out/<name>.glb`` (glTF for any renderer);
3. a picture ``docs/img/example_<name>.png``, made headless in a separate bpy process *through the add-on's own
   operators* (Import Crease Pattern, Fold Crease Pattern), rendered with Workbench: on the left the flat crease
   pattern as drawn (border black, mountain red, valley blue), on the right the folded mesh with its creases, and
   the run's figures (faces, solver time, strain, warp, fold-angle error) in the title.

Then the pins-and-glue demo (issue 17): ``out/ring_glued.svg``, a strip of eight panels between curved valley creases
that stop 5° short of closing, is folded by the command line with ``out/ring_glued.constraints.json`` beside it (its
two short edges glued into a ring, two points of its lower edge pinned to the table 88 mm apart, which pulls the ring
into an oval), and pictured in ``docs/img/pins_glue.png`` through the add-on (Fold, then the ``cf_glue_a``/
``cf_glue_b``/``cf_pins`` vertex groups, Add Pin Hooks, the hooks moved to the targets, Re-solve): the open fold the
creases make alone beside the held one, which neither creases nor glue alone can make.

Then ``docs/img/make_pictures.py`` (the operators' fold-percent / strain / warp pictures) is run on Origami
Simulator's ``wavy_pleats.svg`` from the fixtures vendored in ``tests/fixtures``.

Every step echoes its command and output. Exit code 0 when every step succeeded, 1 otherwise (the failures are
listed at the end). ``cannot_fold.svg`` is meant not to fold as assigned: the demo shows the warning the
command line prints for it (paper Fig. 7) and counts that run as a success.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
IMG = REPO / "docs" / "img"
FIXTURE = REPO / "tests" / "fixtures" / "origami-simulator" / "wavy_pleats.svg"

COLOURS = {"B": "#000000", "M": "#e00000", "V": "#0030ff", "F": "#d8c000", "U": "#c000c0", "C": "#00a000"}
"""Crease-pattern drawing colours per FOLD assignment (Origami Simulator's SVG convention)."""


def _show(path: Path) -> str:
    """``path`` relative to the repository when it is inside it (shorter log lines)."""
    return str(path.relative_to(REPO)) if path.is_relative_to(REPO) else str(path)


def run_step(label: str, argv: list[str]) -> bool:
    """Run ``argv`` in the repository, echoing ``label`` as the command and indenting its output; True on exit 0."""
    print(f"$ {label}", flush=True)
    start = time.perf_counter()
    proc = subprocess.run(argv, cwd=REPO, capture_output=True, text=True)
    for line in (proc.stdout + proc.stderr).strip().splitlines():
        if not line.strip() or "EGL Error" in line or "| INFO:" in line or line.startswith("INFO Draco"):
            continue  # Mesa's harmless EGL_BAD_MATCH lines (blender-notes §4), the glTF exporter's progress lines
        print("    " + line)
    print(f"    -> exit {proc.returncode} in {time.perf_counter() - start:.1f} s", flush=True)
    return proc.returncode == 0


def fold_example(svg: Path, out: Path) -> bool:
    """Fold ``svg`` with the command line into ``out/<name>.fold`` (+ JSON report) and ``out/<name>.glb``."""
    name = svg.stem
    ok = True
    for args in (
        ["fold", _show(svg), "--out", _show(out / f"{name}.fold"), "--report", _show(out / f"{name}.json")],
        ["fold", _show(svg), "--out", _show(out / f"{name}.glb")],
    ):
        ok = run_step("python -m curved_fold " + " ".join(args), [sys.executable, "-m", "curved_fold", *args]) and ok
    return ok


# --------------------------------------------------------------------------------------------------------------
# The picture of one example (runs in its own bpy process: ``python tools/demo.py --picture SVG PNG``).


def _draw_pattern(ax, svg: Path) -> None:
    """Draw the flat crease pattern of ``svg`` (as discretised by the engine) on a matplotlib axis, SVG y-down."""
    from curved_fold.core.io.reader import read_pattern

    pattern = read_pattern(svg)
    v = pattern.vertices
    for a, colour in COLOURS.items():
        idx = [k for k, x in enumerate(pattern.assignments) if x == a]
        if not idx:
            continue
        seg = v[pattern.edges[idx]]
        from matplotlib.collections import LineCollection

        ax.add_collection(LineCollection(seg, colors=colour, linewidths=1.6 if a == "B" else 1.3))
    ax.set_xlim(v[:, 0].min() - 4, v[:, 0].max() + 4)
    ax.set_ylim(v[:, 1].min() - 4, v[:, 1].max() + 4)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title("crease pattern", fontsize=11)


def _fold_with_operators(svg: Path):
    """Import ``svg`` and fold it at 100 % through the add-on's operators; the curves are hidden from renders and the
    folded object is paper-coloured. Returns the folded object."""
    import bpy

    sys.path.insert(0, str(IMG))
    import make_pictures  # the operators helper's render recipe (camera framing, Workbench settings)

    make_pictures.setup_addon()
    assert bpy.ops.curved_fold.import_pattern(filepath=str(svg)) == {"FINISHED"}
    curves = list(bpy.context.selected_objects)
    assert bpy.ops.curved_fold.fold(fold_percent=100.0) == {"FINISHED"}
    ob = bpy.context.active_object
    for c in curves:
        c.hide_render = True
    ob.color = (0.93, 0.9, 0.82, 1)
    return ob


def make_picture(svg: Path, png: Path) -> None:
    """Import ``svg`` through the add-on's operators, fold it, render it with Workbench and write the picture."""
    import bpy

    sys.path.insert(0, str(IMG))
    import make_pictures  # the operators helper's render recipe (camera framing, Workbench settings)

    ob = _fold_with_operators(svg)
    props = ob.curved_fold_mesh
    bpy.context.view_layer.update()
    make_pictures.camera_for([ob], direction=(0.55, -1.0, 0.85), margin=1.08)
    with tempfile.TemporaryDirectory() as tmp:
        render_png = Path(tmp) / "render.png"
        make_pictures.render(render_png, "OBJECT", width=900, height=700)
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.image as mpimg
        import matplotlib.pyplot as plt

        figures = (
            f"strain {props.last_strain_mean:.2f} % mean / {props.last_strain_max:.2f} % max, "
            f"warp {props.last_warp_mean:.2f}° mean, fold-angle error {props.last_fold_error:.1f}° mean, "
            f"solver {props.last_ms:.0f} ms, {props.last_iterations} iterations"
            + ("" if props.last_converged else " (NOT converged)")
        )
        lines = [f"examples/{svg.name}", figures, *textwrap.wrap(props.last_message, 120)]
        head = 0.25 * len(lines) + 0.15  # inches of title
        fig, (left, right) = plt.subplots(1, 2, figsize=(12, 5.0 + head), gridspec_kw={"width_ratios": [1, 1.25]})
        _draw_pattern(left, svg)
        right.imshow(mpimg.imread(render_png))
        right.axis("off")
        right.set_title(f"folded 100 % ({props.last_faces} faces, ruling mesh, fast solver)", fontsize=11)
        fig.suptitle("\n".join(lines), fontsize=10.5, color="#a00000" if props.last_message else "black")
        fig.subplots_adjust(left=0.02, right=0.98, bottom=0.02, top=1 - (head + 0.35) / (5.0 + head), wspace=0.06)
        png.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(png, dpi=90, facecolor="white")
    print(f"{svg.name}: {props.last_faces} faces, {figures}")
    if props.last_message:
        print(f"{svg.name}: {props.last_message}")
    print(f"wrote {png}")


RING_W, RING_H, RING_PANELS, RING_CREASE_DEG = 240.0, 60.0, 8, 40.0
RING_CONSTRAINTS = {
    "glue": [[[0.0, 0.0], [RING_W, 0.0]], [[0.0, -RING_H], [RING_W, -RING_H]]],
    "pins": [
        {"point": [60.0, -RING_H], "target": [60.0, -RING_H, 0.0]},
        {"point": [180.0, -RING_H], "target": [148.0, -RING_H, 0.0]},
    ],
}
"""Glue the strip's short edges (a ring); pin two lower crease ends on the table 88 mm apart (the round ring would
hold them about 75 mm apart), in pattern coordinates (mm, SVG y negated)."""


def ring_svg() -> str:
    """The ring strip: eight panels between curved valley creases of 40° (a closed octagon needs 45°)."""
    paths = "".join(
        f'  <path d="M {x:g} 0 C {x + 7:g} 20 {x + 7:g} 40 {x:g} {RING_H:g}" fill="none" stroke="#0000ff" '
        f'opacity="{RING_CREASE_DEG / 180:.6f}"/>\n'
        for x in (RING_W * k / RING_PANELS for k in range(1, RING_PANELS))
    )
    return (
        '<?xml version="1.0" encoding="utf-8"?>\n'
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{RING_W:g}mm" height="{RING_H:g}mm" '
        f'viewBox="0 0 {RING_W:g} {RING_H:g}">\n  <title>ring strip for pins and glue</title>\n'
        f'  <rect x="0" y="0" width="{RING_W:g}" height="{RING_H:g}" fill="none" stroke="#000000"/>\n{paths}</svg>\n'
    )


def make_pins_picture(svg: Path, png: Path) -> None:
    """Fold the ring strip with the add-on's operators, then glue and pin it with vertex groups and hook empties,
    re-solve, and picture the pattern, the open fold and the held fold side by side."""
    import bpy
    import numpy as np

    sys.path.insert(0, str(IMG))
    import make_pictures

    from curved_fold.scene import mesh_object, pins

    ob = _fold_with_operators(svg)
    props = ob.curved_fold_mesh
    open_figures = f"creases alone: open, {props.last_iterations} iterations"
    flat = np.empty(2 * len(ob.data.vertices), np.float32)
    ob.data.attributes["cf_flat"].data.foreach_get("vector", flat)
    flat = flat.reshape(-1, 2).astype(np.float64)

    def vertex(point) -> int:
        return int(np.argmin(np.linalg.norm(flat - np.asarray(point, float), axis=1)))

    glue = RING_CONSTRAINTS["glue"]
    ob.vertex_groups.new(name="cf_glue_a").add([vertex(a) for a, _ in glue], 1.0, "REPLACE")
    ob.vertex_groups.new(name="cf_glue_b").add([vertex(b) for _, b in glue], 1.0, "REPLACE")
    pinned = {vertex(p["point"]): p["target"] for p in RING_CONSTRAINTS["pins"]}
    ob.vertex_groups.new(name="cf_pins").add(list(pinned), 1.0, "REPLACE")
    with tempfile.TemporaryDirectory() as tmp:
        open_png, held_png = Path(tmp) / "open.png", Path(tmp) / "held.png"
        bpy.context.view_layer.update()
        make_pictures.camera_for([ob], direction=(0.35, -1.0, 0.6), margin=1.08)
        make_pictures.render(open_png, "OBJECT", width=700, height=600)
        assert bpy.ops.curved_fold.add_pin_hooks() == {"FINISHED"}
        mm = mesh_object.mm_per_unit(bpy.context.scene)
        for k, empty in pins.pin_hooks(ob).items():
            empty.location = [c / mm for c in pinned[k]]  # drag each hook to its target
        assert bpy.ops.curved_fold.refold(rebuild="RESOLVE") == {"FINISHED"}
        bpy.data.objects.remove(bpy.context.scene.camera)
        bpy.context.view_layer.update()
        make_pictures.camera_for([ob], direction=(0.35, -1.0, 0.6), margin=1.08)
        make_pictures.render(held_png, "OBJECT", width=700, height=600)
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.image as mpimg
        import matplotlib.pyplot as plt

        crossing = ob.get("cf_self_intersecting_faces", -1)
        figures = (
            f"glued + pinned: {props.last_iterations} iterations, {props.last_ms:.0f} ms"
            + ("" if props.last_converged else " (NOT converged)")
            + f", glue gap {ob['cf_glue_gap_mm']:.1e} mm, pins on target, strain {props.last_strain_mean:.2f} % "
            f"mean / {props.last_strain_max:.2f} % max, self-intersecting faces {crossing}"
        )
        fig, axes = plt.subplots(1, 3, figsize=(15, 4.6), gridspec_kw={"width_ratios": [1.3, 1, 1]})
        _draw_pattern(axes[0], svg)
        axes[0].set_title("ring strip: creases 40° (a closed ring needs 45°)", fontsize=11)
        for ax, image, title in (
            (axes[1], open_png, open_figures),
            (axes[2], held_png, "ends glued, lower edge pinned 88 mm apart"),
        ):
            ax.imshow(mpimg.imread(image))
            ax.axis("off")
            ax.set_title(title, fontsize=11)
        fig.suptitle(f"Pins and glue (out/{svg.name})\n{figures}", fontsize=10.5)
        fig.subplots_adjust(left=0.01, right=0.99, bottom=0.02, top=0.82, wspace=0.04)
        png.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(png, dpi=90, facecolor="white")
    print(figures)
    print(f"wrote {png}")


def pins_glue_step(out: Path, img: Path, pictures: bool) -> bool:
    """Write the ring strip and its constraints beside it, fold it with the command line, then picture it."""
    from curved_fold.core.io.atomic import atomic_write_text

    svg = out / "ring_glued.svg"
    atomic_write_text(svg, ring_svg())
    atomic_write_text(out / "ring_glued.constraints.json", json.dumps(RING_CONSTRAINTS, indent=1) + "\n")
    args = ["fold", _show(svg), "--out", _show(out / "ring_glued.fold"), "--report", _show(out / "ring_glued.json")]
    ok = run_step("python -m curved_fold " + " ".join(args), [sys.executable, "-m", "curved_fold", *args])
    if ok and pictures:
        png = img / "pins_glue.png"
        label = f"python tools/demo.py --pins-picture {_show(svg)} {_show(png)}"
        ok = run_step(label, [sys.executable, str(Path(__file__).resolve()), "--pins-picture", str(svg), str(png)])
    return ok


def picture_step(svg: Path, png: Path) -> bool:
    """Make the picture of one example in a fresh bpy process (the add-on registers once per process)."""
    label = f"python tools/demo.py --picture {_show(svg)} {_show(png)}"
    return run_step(label, [sys.executable, str(Path(__file__).resolve()), "--picture", str(svg), str(png)])


def operator_pictures() -> bool:
    """Run ``docs/img/make_pictures.py`` (fold percents, strain and warp colours of Jun Mitani's ``wavy_pleats.svg``).

    The pictures and the guide's captions are of that fixture (vendored with its licence and credit).
    """
    script = IMG / "make_pictures.py"
    return run_step(f"python {_show(script)} {_show(FIXTURE)}", [sys.executable, str(script), str(FIXTURE)])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--examples", type=Path, default=REPO / "examples", help="folder of .svg patterns")
    parser.add_argument("--out", type=Path, default=REPO / "out", help="folder for the folded meshes")
    parser.add_argument("--img", type=Path, default=IMG, help="folder for the pictures")
    parser.add_argument("--no-pictures", action="store_true", help="fold only, render nothing")
    parser.add_argument("--picture", nargs=2, type=Path, metavar=("SVG", "PNG"), help=argparse.SUPPRESS)
    parser.add_argument("--pins-picture", nargs=2, type=Path, metavar=("SVG", "PNG"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.picture:
        make_picture(args.picture[0].resolve(), args.picture[1].resolve())
        return 0
    if args.pins_picture:
        make_pins_picture(args.pins_picture[0].resolve(), args.pins_picture[1].resolve())
        return 0
    svgs = sorted(args.examples.resolve().glob("*.svg"))
    if not svgs:
        print(f"demo: no .svg patterns in {args.examples}", file=sys.stderr)
        return 1
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    failed: list[str] = []
    start = time.perf_counter()
    for svg in svgs:
        print(f"== {_show(svg)} ==", flush=True)
        if not fold_example(svg, out):
            failed.append(f"fold {svg.name}")
            continue
        report = json.loads((out / f"{svg.stem}.json").read_text(encoding="utf-8"))
        if report.get("does_not_fold_as_assigned"):
            expected = svg.stem == "cannot_fold"
            print(f"    ({'expected: this pattern cannot fold' if expected else 'UNEXPECTED'}: see the warning above)")
        if not args.no_pictures and not picture_step(svg, args.img.resolve() / f"example_{svg.stem}.png"):
            failed.append(f"picture {svg.name}")
    print("== pins and glue ==", flush=True)
    if not pins_glue_step(out, args.img.resolve(), not args.no_pictures):
        failed.append("pins and glue")
    if not args.no_pictures:
        print("== operator pictures ==", flush=True)
        if not operator_pictures():
            failed.append("docs/img/make_pictures.py")
    took = time.perf_counter() - start
    print(f"demo: {len(svgs)} examples, folded meshes in {_show(out)}, pictures in {_show(args.img.resolve())}")
    if failed:
        print(f"demo: FAILED: {', '.join(failed)} ({took:.0f} s)")
        return 1
    print(f"demo: all steps succeeded ({took:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
