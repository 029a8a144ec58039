"""Mesh statistics in the layout of the paper's Table 1 (#F, generation ms) for earcut, CDT and ruling meshes.

Run: ``.venv/bin/python -m curved_fold.benchmarks.mesh_table`` (or ``python benchmarks/mesh_table.py``).
Prints the table and writes it into ``docs/meshes.md`` between its generated-section markers (the design notes
around it are written by hand), and ``docs/img/meshes_single_curve.png``
(the three meshes of one single-curve pattern side by side, like the paper's Fig. 5).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
FIXTURES = REPO / "tests" / "fixtures"
MESH_TYPES = ("earcut", "cdt", "ruling")


def _inputs() -> list[Path]:
    paths = sorted((FIXTURES / "origami-simulator").glob("*.svg"))  # tests/fixtures/fold holds file-format cases
    examples = REPO / "examples"
    if examples.is_dir():
        paths += sorted(examples.glob("*.svg")) + sorted(examples.glob("*.fold"))
    return paths


def _reference_build_mesh():
    """The frozen first implementation (tests/mesh_reference), for the "before" columns; None if absent."""
    try:
        from curved_fold.tests.mesh_reference.meshing import build_mesh
    except ImportError:  # pragma: no cover - the tests folder is not shipped with the extension
        return None
    return build_mesh


def measure(path: Path, repeats: int, before: bool = True) -> dict:
    """#F, median generation ms and swaps per mesh type; with ``before`` also the reference implementation's ms."""
    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.mesh.build import build_mesh

    pattern = read_pattern(path)
    reference = _reference_build_mesh() if before else None
    row = {"name": path.name, "vertices": pattern.n_vertices, "curve_segments": int(pattern.edge_from_curve.sum())}
    for mesh_type in MESH_TYPES:
        build_mesh(pattern, mesh_type)  # warm-up (imports, caches)
        runs = [build_mesh(pattern, mesh_type) for _ in range(repeats)]
        row[mesh_type] = {
            "faces": runs[0].n_faces,
            "ms": statistics.median(r.generation_ms for r in runs),
            "swaps": runs[0].swaps,
        }
        if reference is not None:
            row[mesh_type]["before_ms"] = statistics.median(
                reference(pattern, mesh_type).generation_ms for _ in range(repeats)
            )
    return row


def single_curve_pattern():
    """A 150 mm square with one S-shaped Bézier valley crease from the left to the right edge (paper Fig. 5 style)."""
    from curved_fold.core.pattern.discretize import discretize
    from curved_fold.core.pattern.model import CreaseCurve, CurveSegment

    s = 150.0
    crease = CurveSegment("cubic", np.array([[0.0, 60.0], [50.0, 140.0], [100.0, 10.0], [s, 90.0]]))
    curves = [CreaseCurve([crease], "V", 108.0, source="single curve")]
    corners = np.array([[0, 0], [s, 0], [s, s], [0, s]], dtype=float)
    for k in range(4):
        seg = CurveSegment("line", np.array([corners[k], corners[(k + 1) % 4]]))
        curves.append(CreaseCurve([seg], "B", None, source=f"border {k}"))
    return discretize(curves, interval=7.0, tolerance=0.07)


def draw_meshes(path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    from curved_fold.core.mesh.build import build_mesh

    pattern = single_curve_pattern()
    fig, axes = plt.subplots(1, 3, figsize=(15, 5.8))
    titles = {
        "earcut": "(a) ear clipping (Origami Simulator)",
        "cdt": "(b) constrained Delaunay",
        "ruling": "(c) ruling-aware swaps",
    }
    colours = {"B": "black", "M": "red", "V": "blue", "F": "0.6", "U": "magenta"}
    for ax, mesh_type in zip(axes, MESH_TYPES, strict=True):
        mesh = build_mesh(pattern, mesh_type)
        order = np.argsort(mesh.assignments != "F", kind="stable")  # facets first, creases on top
        segs = mesh.vertices[mesh.edges[order]]
        cols = [colours.get(a, "green") for a in mesh.assignments[order]]
        widths = [0.6 if a == "F" else 1.6 for a in mesh.assignments[order]]
        ax.add_collection(LineCollection(segs, colors=cols, linewidths=widths))
        ax.set_xlim(-3, 153)
        ax.set_ylim(-3, 153)
        ax.set_aspect("equal")
        ax.axis("off")
        extra = f", {mesh.swaps} swaps" if mesh_type == "ruling" else ""
        ax.set_title(f"{titles[mesh_type]}\n{mesh.n_faces} faces{extra}", fontsize=11)
    fig.tight_layout(pad=1.5)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


MESH_BEGIN = "<!-- BEGIN GENERATED: benchmarks/mesh_table.py -->"
MESH_END = "<!-- END GENERATED: benchmarks/mesh_table.py -->"


def render_markdown(rows: list[dict], repeats: int, load: str = "") -> str:
    """The generated section of ``docs/meshes.md`` (between :data:`MESH_BEGIN` and :data:`MESH_END`): how it was
    measured and the table; the design notes around it are written by hand in the document."""
    lines = [
        MESH_BEGIN,
        "Generated by `.venv/bin/python -m curved_fold.benchmarks.mesh_table` (median of "
        f"{repeats} runs; generation = triangulation + swaps, wall time, default backend, 2-core CI-class machine"
        + (f", load average {load} during the run, so other jobs shared the cores)." if load else ")."),
        "Inputs: every pattern in `tests/fixtures/origami-simulator` and every example in `examples/`, read with "
        "`core.io.reader.read_pattern` at the default discretisation parameters.",
        "",
        "| Pattern | #V | curve segs | earcut #F | earcut ms | CDT #F | CDT ms | ruling #F | ruling ms | swaps |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['name']} | – | – | error: {r['error']} | | | | | | |")
            continue
        e, c, g = r["earcut"], r["cdt"], r["ruling"]
        lines.append(
            f"| {r['name']} | {r['vertices']} | {r['curve_segments']} | {e['faces']} | {e['ms']:.1f} | {c['faces']} | "
            f"{c['ms']:.1f} | {g['faces']} | {g['ms']:.1f} | {g['swaps']} |"
        )
    timed = [r for r in rows if "error" not in r and "before_ms" in r["ruling"]]
    if timed:
        lines += [
            "",
            "Before and after the speed-up (same run, same machine, median of "
            f"{repeats}; before = the first implementation in `tests/mesh_reference/`):",
            "",
            "| Pattern | #F | swaps | earcut ms before → after | CDT ms before → after | ruling ms before → after "
            "| swaps ms before → after |",
            "|---|---:|---:|---:|---:|---:|---:|",
        ]
        for r in timed:
            e, c, g = r["earcut"], r["cdt"], r["ruling"]
            sb, sa = g["before_ms"] - c["before_ms"], g["ms"] - c["ms"]
            lines.append(
                f"| {r['name']} | {g['faces']} | {g['swaps']} | {e['before_ms']:.1f} → {e['ms']:.1f} | "
                f"{c['before_ms']:.1f} → {c['ms']:.1f} | {g['before_ms']:.1f} → {g['ms']:.1f} | "
                f"{sb:.1f} → {sa:.1f} |"
            )
    lines.append(MESH_END)
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--no-before", action="store_true", help="skip timing the frozen first implementation")
    parser.add_argument("--no-write", action="store_true", help="print only, do not write docs/")
    args = parser.parse_args(argv)
    rows = []
    load0 = os.getloadavg()[0]
    for path in _inputs():
        try:
            rows.append(measure(path, args.repeats, before=not args.no_before))
        except Exception as exc:  # report and continue: the table should show every input
            rows.append({"name": path.name, "error": f"{type(exc).__name__}: {exc}"[:120]})
    load = f"{load0:.1f}–{os.getloadavg()[0]:.1f}"
    md = render_markdown(rows, args.repeats, load)
    print(md)
    if not args.no_write:
        from curved_fold.benchmarks.common import replace_section

        replace_section(REPO / "docs" / "meshes.md", MESH_BEGIN, MESH_END, md)
        draw_meshes(REPO / "docs" / "img" / "meshes_single_curve.png")
        print("wrote the table in docs/meshes.md and docs/img/meshes_single_curve.png")
    return 0


if __name__ == "__main__":
    if __package__ in (None, ""):
        sys.path.insert(0, str(REPO.parent))
    sys.exit(main())
