"""Jobs benchmark (issue 13): how long the longest slice of a sliced Fold is on each fixture, how long a 100-frame
bake of CircularPleat-antiFacet takes, and how long a live re-fold takes after one curve edit on Treble_Clef.

Runs in bpy (the add-on registered from this checkout): ``python -m curved_fold.benchmarks.jobs [--fixtures A B]
[--frames 100]``. Prints a markdown table for docs/benchmarks.md. Measures only; asserts nothing.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from .common import FIXTURES, load_average


def _run_timed(jobs, job, budget: float) -> float:
    """Run ``job`` slice by slice to its end, as the modal operator does; returns the longest slice in ms."""
    longest = 0.0
    while True:
        ts = time.perf_counter()
        ended = jobs.run_slice(job, budget)
        longest = max(longest, 1e3 * (time.perf_counter() - ts))
        if ended:
            return longest


def _fold(bpy, folding, jobs, path, budget_ms):
    coll_before = set(bpy.data.collections)
    from ..scene.import_curves import import_crease_pattern

    objects, _ = import_crease_pattern(str(path))
    coll = next(iter(set(bpy.data.collections) - coll_before))
    sources = folding.curve_objects(objects)
    t0 = time.perf_counter()
    job = jobs.start(folding.fold_job(sources, coll, folding.FoldOptions()))
    units_ms = []
    while True:
        ts = time.perf_counter()
        ended = jobs.run_slice(job, budget_ms)
        units_ms.append(1e3 * (time.perf_counter() - ts))
        if ended:
            break
    wall = time.perf_counter() - t0
    ob, out = job.result
    return ob, out, job, wall, units_ms


def main(argv=None) -> int:
    import bpy

    import curved_fold

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fixtures", nargs="*", default=None)
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument(
        "--bake-from", choices=("svg", "import"), default="svg", help="bake the CLI's mesh or the imported curves'"
    )
    parser.add_argument("--budget", type=float, default=None, help="slice budget in ms (default jobs.SLICE_MS)")
    args = parser.parse_args(argv)
    bpy.ops.wm.read_homefile(use_empty=True)
    curved_fold.register()
    from curved_fold.scene import bake, folding, jobs, live

    budget = args.budget or jobs.SLICE_MS
    la = load_average()
    print(f"load average {la[0]:.1f} / {la[1]:.1f} / {la[2]:.1f}; slice budget {budget:.0f} ms")
    names = args.fixtures or sorted(p.name for p in FIXTURES.glob("*.svg"))
    print(
        "| pattern | #F | slices | longest slice ms | median slice ms | read curves ms | discretise ms (longest "
        "step) | mesh ms | model ms | longest iteration ms | iterations | fold wall s |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    folded = {}
    for name in names:
        bpy.ops.wm.read_homefile(use_empty=True)
        ob, out, job, wall, slices = _fold(bpy, folding, jobs, FIXTURES / name, budget)
        folded[name] = ob.name
        print(
            f"| {name} | {out.mesh.n_faces} | {len(slices)} | {max(slices):.0f} | {np.median(slices):.0f} | "
            + " | ".join(f"{job.unit_ms.get(k, 0):.0f}" for k in ("start", "discretise", "mesh", "model", "solve"))
            + f" | {out.report['iterations']} | {wall:.1f} |",
            flush=True,
        )
    if args.frames:
        bpy.ops.wm.read_homefile(use_empty=True)
        if args.bake_from == "import":
            ob, out, *_ = _fold(bpy, folding, jobs, FIXTURES / "CircularPleat-antiFacet.svg", math.inf)
            n_faces = out.mesh.n_faces
        else:  # the mesh the command line builds from the SVG (the 3,000 faces of the other tables)
            from curved_fold.core.io.reader import read_pattern
            from curved_fold.core.mesh.build import build_mesh
            from curved_fold.scene import mesh_object

            mesh = build_mesh(read_pattern(FIXTURES / "CircularPleat-antiFacet.svg"))
            ob = mesh_object.create_fold_object(mesh, mesh.vertices_3d, "CircularPleat", bpy.context.scene.collection)
            ob.curved_fold_mesh.is_fold_mesh = True
            n_faces = mesh.n_faces
        frames = list(range(1, args.frames + 1))
        t0 = time.perf_counter()
        job = jobs.start(bake.bake_job(ob, frames))
        longest = _run_timed(jobs, job, budget)
        summary = job.result
        print(
            f"\nbake CircularPleat-antiFacet ({n_faces} faces, {args.bake_from}), {len(frames)} frames 0 → 100 %: "
            f"{time.perf_counter() - t0:.1f} s wall, {summary.iterations} Newton iterations "
            f"({summary.iterations / len(frames):.1f} per frame), longest slice {longest:.0f} ms, "
            f"unconverged frames {len(summary.unconverged)}",
            flush=True,
        )
    bpy.ops.wm.read_homefile(use_empty=True)
    ob, out, *_ = _fold(bpy, folding, jobs, FIXTURES / "Treble_Clef.svg", math.inf)
    for mode in ("settings", "curve"):
        if mode == "settings":
            ob.curved_fold_mesh.fold_percent = 90.0
            rebuild = False
        else:
            src = folding.source_objects(ob)
            crease = next(s for s in src if s.curved_fold.role in ("MOUNTAIN", "VALLEY"))
            bp = next(sp for sp in crease.data.splines if len(sp.bezier_points) >= 2).bezier_points[1]
            size = max(crease.dimensions.x, crease.dimensions.y, 1e-6)
            bp.co.x += 0.002 * size
            bp.handle_left.x += 0.002 * size
            bp.handle_right.x += 0.002 * size
            rebuild = True
        t0 = time.perf_counter()
        job = jobs.start(
            folding.refold_job(
                ob,
                rebuild=None if rebuild else False,
                max_iterations=live.LIVE_MAX_ITERATIONS,
                warm_start=True,
                live=True,
            )
        )
        longest = _run_timed(jobs, job, budget)
        res = job.result
        print(
            f"live re-fold Treble_Clef after a {mode} edit: {time.perf_counter() - t0:.2f} s wall, "
            f"{res.report['iterations']} iterations, converged {res.report['converged']}, residual "
            f"{res.report['residual']:.1e}, longest slice {longest:.0f} ms",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
