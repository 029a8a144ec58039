"""``curved_fold discretize INPUT --out OUT.fold``: discretise a crease pattern and write it as FOLD.

Prints the parameters used (marking the scale-aware defaults), the vertex count, the segment count per assignment
and from curves, every warning, and where the file went. Bad input exits with code 2 and one line on stderr
(handled by ``cli.main``).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..core.pattern.model import ASSIGNMENT_NAMES, ASSIGNMENTS, PatternError
from .outputs import check_outputs
from .progress import Progress


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``discretize`` subcommand."""
    p = sub.add_parser(
        "discretize",
        help="discretise curves (SVG, .blend) into straight segments and write a FOLD crease pattern",
        description="Discretise a crease pattern (paper §3.1) and write it as a 2D FOLD file in millimetres.",
    )
    p.add_argument("input", help="crease pattern: .svg (Origami Simulator colours), .fold or .blend")
    p.add_argument("--out", required=True, help="FOLD file to write")
    p.add_argument("--interval", type=float, default=None, help="maximum chord / border piece length, mm")
    p.add_argument("--tolerance", type=float, default=None, help="maximum curve-to-chord distance, mm")
    p.add_argument("--merge", type=float, default=None, help="merge vertices closer than this, mm")
    p.add_argument(
        "--collection",
        default=None,
        help="of a .blend input: discretise this collection's crease curves (default: its scene's)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors (no summary, no progress)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``discretize``; returns the exit code."""
    import time

    from ..core.io.fold import is_our_pattern, read_fold, write_pattern_fold
    from ..core.io.reader import read_curves, read_pattern
    from ..core.pattern.discretize import default_parameters, discretize, pattern_sheet_size, sheet_size

    path = Path(args.input)
    out = Path(args.out)
    if out.suffix.lower() != ".fold":
        raise PatternError(f"--out {out}: the output must be a .fold file")
    for name in ("interval", "tolerance", "merge"):
        value = getattr(args, name)
        if value is not None and not (value > 0 and math.isfinite(value)):
            raise PatternError(f"--{name} {value:g}: must be a positive number of mm")
    check_outputs(path, {"--out": out})
    t0 = time.perf_counter()
    is_fold = path.suffix.lower() == ".fold"
    with Progress(quiet=args.quiet).stage(f"{path.name}"):
        if is_fold:
            pattern = read_pattern(path, interval=args.interval, tolerance=args.tolerance, collection=args.collection)
            ours = is_our_pattern(read_fold(path))  # read again, once read_pattern has checked the file
        else:
            curves, warnings = read_curves(path, collection=args.collection)
            pattern = discretize(curves, interval=args.interval, tolerance=args.tolerance, merge_tolerance=args.merge)
            pattern.warnings = warnings + pattern.warnings
    ms = (time.perf_counter() - t0) * 1e3
    written = write_pattern_fold(out, pattern)  # first: the summary below may meet a closed pipe (`| head`)
    if args.quiet:
        return 0
    print(f"read {path} ({ms:.0f} ms)")
    if is_fold and ours:
        print("parameters: none (a FOLD file of ours: its segments are read back as written)")
    else:
        if is_fold:  # no merge tolerance: a FOLD file's vertices are taken as they are
            size, names = pattern_sheet_size(pattern), ("interval", "tolerance")
            print(
                f"sheet size {size:.3f} mm (another tool's FOLD file: its dense polylines thinned, border and cuts "
                "split)"
            )
        else:
            size, names = sheet_size(curves), ("interval", "tolerance", "merge")
            basis = "the border" if any(c.assignment == "B" for c in curves) else "all curves (no border)"
            print(f"sheet size {size:.3f} mm (largest extent of {basis})")
        defaults = dict(zip(("interval", "tolerance", "merge"), default_parameters(size), strict=True))
        for name in names:
            label = "merge tolerance" if name == "merge" else name
            given = getattr(args, name)
            if given is None:
                print(f"  {label}: {defaults[name]:.4g} mm (default, scale-aware)")
            else:
                print(f"  {label}: {given:.4g} mm (given)")
    print(f"vertices: {pattern.n_vertices}")
    counts = ", ".join(f"{a} {pattern.count(a)}" for a in ASSIGNMENTS)
    print(f"segments: {pattern.n_edges} ({counts})")
    for a in ASSIGNMENTS:
        if pattern.count(a):
            print(f"  {ASSIGNMENT_NAMES[a]}: {pattern.count(a)}")
    print(f"from curves: {int(pattern.edge_from_curve.sum())}")
    for w in pattern.warnings:
        print(f"warning: {w}")
    print(f"wrote {written}")
    return 0
