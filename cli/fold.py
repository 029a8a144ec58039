"""``fold``: read a pattern, triangulate, fold to equilibrium, write the folded mesh (and a JSON report)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ..core.pattern.model import PatternError

OUTPUT_SUFFIXES = (".fold", ".obj", ".glb", ".blend")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``fold`` subcommand."""
    p = sub.add_parser("fold", help="fold a crease pattern (.svg/.fold/.blend) and write the folded mesh")
    p.add_argument("input", help="crease pattern: .svg, .fold or .blend")
    p.add_argument("--out", required=True, help="output: .fold, .obj, .glb or .blend")
    p.add_argument("--angle", type=float, default=None, help="fold angle (deg) for creases without one")
    p.add_argument("--percent", type=float, default=100.0, help="fold percent, 0–100 (default 100)")
    p.add_argument("--interval", type=float, default=None, help="max chord length of discretised curves (mm)")
    p.add_argument("--tolerance", type=float, default=None, help="max curve deviation of a chord (mm)")
    p.add_argument("--mesh", default="ruling", choices=("ruling", "cdt", "earcut"), help="triangulation")
    p.add_argument("--solver", default="fast", choices=("fast", "faithful", "isometric"), help="solver method")
    p.add_argument("--report", default=None, help="write the report as JSON here")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..core.io.reader import read_pattern
    from ..core.pipeline import fold_pattern

    out = Path(args.out)
    if out.suffix.lower() not in OUTPUT_SUFFIXES:
        raise PatternError(f"--out {out}: unknown output type {out.suffix!r}; use one of {', '.join(OUTPUT_SUFFIXES)}")
    pattern = read_pattern(args.input, interval=args.interval, tolerance=args.tolerance)
    fold = fold_pattern(
        pattern, angle=args.angle, percent=args.percent / 100.0, mesh_type=args.mesh, solver=args.solver
    )
    r = fold.report
    if out.suffix.lower() == ".fold":
        from ..core.io.fold import write_folded_fold

        write_folded_fold(out, fold.mesh, [fold.result.positions], [fold.result.fold_angles])
    else:
        try:
            from ..scene.export import export_folded_file
        except ImportError as exc:  # pragma: no cover - depends on the Blender side being installed
            raise PatternError(f"--out {out}: {out.suffix} output needs Blender's bpy ({exc})") from exc
        export_folded_file(out, fold.mesh, fold.result.positions, fold_angles=fold.result.fold_angles)
    if args.report:
        from ..core.io.atomic import atomic_write_text

        clean = {k: (None if isinstance(v, float) and v != v else v) for k, v in r.items()}  # NaN is not JSON
        atomic_write_text(args.report, json.dumps(clean, indent=2, default=float))
    print(
        f"{args.input}: {r['faces']} faces ({r['mesh_type']}, {r['generation_ms']:.0f} ms), "
        f"{r['solver']} solver {r['simulation_ms']:.0f} ms, {r['iterations']} iterations, "
        f"{'converged' if r['converged'] else 'NOT converged'} (residual {r['residual']:.1e})"
    )
    print(
        f"strain mean {r['strain_mean_pct']:.3f} % max {r['strain_max_pct']:.3f} %, warp mean "
        f"{r['warp_mean_deg']:.2f}°, fold-angle error {r['fold_angle_error_mean_deg']:.2f}° → {out}"
    )
    if r.get("does_not_fold_as_assigned"):
        print("warning: " + r["does_not_fold_message"])
    for w in r.get("warnings", [])[:5]:
        print("warning: " + str(w))
    return 0
