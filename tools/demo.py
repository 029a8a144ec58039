"""``make demo``: run the command line on every example pattern in ``examples/`` and write the results to ``out/``.

For each ``examples/*.svg``:

* if the ``fold`` subcommand exists, ``python -m curved_fold fold <svg> --out out/<name>.fold`` and ``--out
  out/<name>.glb``, then a Workbench picture ``out/<name>.png`` of the folded ``.glb`` (headless Blender);
* otherwise ``python -m curved_fold discretize <svg> --out out/<name>.fold`` and a clear message that the demo
  stopped after discretising (the solver is not there yet): nothing is ever presented as folded that was not.

Exit code: 0 when every example went through every step available, 1 otherwise.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def available_subcommands() -> set[str]:
    """Names of the subcommands the package's command line offers (read from its argparse parser)."""
    sys.path.insert(0, str(REPO / ".venv" / "links"))  # harmless if curved_fold is already importable
    from curved_fold.cli import build_parser

    parser = build_parser()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return set(action.choices)
    return set()


def run_cli(args: list[str]) -> bool:
    """Run ``python -m curved_fold <args>``, echoing the command and its output; True on exit code 0."""
    print("$ python -m curved_fold " + " ".join(args), flush=True)
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "curved_fold", *args], cwd=REPO, capture_output=True, text=True)
    for line in (proc.stdout + proc.stderr).strip().splitlines():
        print("    " + line)
    print(f"    -> exit {proc.returncode} in {time.perf_counter() - start:.1f} s", flush=True)
    return proc.returncode == 0


RENDER_SCRIPT = r"""
import math, sys
import bpy
from mathutils import Vector

glb, png = sys.argv[1], sys.argv[2]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=glb)
meshes = [ob for ob in bpy.context.scene.objects if ob.type == "MESH"]
if not meshes:
    raise SystemExit(f"{glb}: no mesh to render")
scene = bpy.context.scene
scene.frame_set(scene.frame_end)
points = [ob.matrix_world @ Vector(c) for ob in meshes for c in ob.bound_box]
lo = Vector([min(p[i] for p in points) for i in range(3)])
hi = Vector([max(p[i] for p in points) for i in range(3)])
centre, size = (lo + hi) / 2, max((hi - lo).length, 1e-6)
cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
scene.collection.objects.link(cam)
direction = Vector((1.0, -1.0, 0.8)).normalized()
cam.location = centre + direction * size * 1.6
cam.rotation_euler = (-direction).to_track_quat("-Z", "Y").to_euler()
scene.camera = cam
scene.render.engine = "BLENDER_WORKBENCH"
scene.display.shading.light = "STUDIO"
scene.display.shading.color_type = "SINGLE"
scene.display.shading.show_cavity = True
scene.render.film_transparent = True
scene.render.resolution_x, scene.render.resolution_y = 640, 480
scene.render.image_settings.file_format = "PNG"
scene.render.filepath = png
bpy.ops.render.render(write_still=True)
"""


def render(glb: Path, png: Path) -> bool:
    """Render the last frame of a folded ``.glb`` to ``png`` with Workbench in a separate headless process."""
    print(f"$ render {glb.relative_to(REPO)} -> {png.relative_to(REPO)}", flush=True)
    proc = subprocess.run(
        [sys.executable, "-c", RENDER_SCRIPT, str(glb), str(png)], capture_output=True, text=True, cwd=REPO
    )
    ok = proc.returncode == 0 and png.is_file()
    if not ok:
        print("    " + (proc.stdout + proc.stderr).strip().replace("\n", "\n    "))
    print(f"    -> {'ok' if ok else 'FAILED'}", flush=True)
    return ok


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--examples", type=Path, default=REPO / "examples", help="folder of .svg patterns")
    parser.add_argument("--out", type=Path, default=REPO / "out", help="output folder")
    args = parser.parse_args(argv)
    svgs = sorted(args.examples.glob("*.svg"))
    if not svgs:
        print(f"demo: no .svg patterns in {args.examples}", file=sys.stderr)
        return 1
    args.out.mkdir(parents=True, exist_ok=True)
    commands = available_subcommands()
    if not commands & {"fold", "discretize"}:
        print("demo: the command line has neither a 'fold' nor a 'discretize' subcommand yet", file=sys.stderr)
        return 1
    failures = 0
    for svg in svgs:
        name = svg.stem
        print(f"== {svg.relative_to(REPO) if svg.is_relative_to(REPO) else svg} ==", flush=True)
        if "fold" in commands:
            ok = run_cli(["fold", str(svg), "--out", str(args.out / f"{name}.fold")])
            ok = run_cli(["fold", str(svg), "--out", str(args.out / f"{name}.glb")]) and ok
            if ok:
                ok = render(args.out / f"{name}.glb", args.out / f"{name}.png")
        else:
            ok = run_cli(["discretize", str(svg), "--out", str(args.out / f"{name}.fold")])
        failures += not ok
    if "fold" not in commands:
        print(
            "demo: STOPPED AFTER DISCRETISING — the 'fold' subcommand (solver) does not exist yet, so out/*.fold are "
            "flat crease patterns, not folded shapes."
        )
    print(f"demo: {len(svgs) - failures}/{len(svgs)} examples done, outputs in {args.out}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
