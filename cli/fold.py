"""``fold``: read a pattern, triangulate, fold to equilibrium, write the folded mesh (and a JSON report)."""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
from collections.abc import Iterator
from pathlib import Path

from ..core.io.atomic import OutputError, atomic_output
from ..core.pattern.model import PatternError
from .outputs import check_outputs, finite_json, stdout_to_devnull
from .progress import Progress

OUTPUT_SUFFIXES = (".fold", ".obj", ".stl", ".glb", ".gltf", ".blend", ".svg")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``fold`` subcommand."""
    p = sub.add_parser("fold", help="fold a crease pattern (.svg/.fold/.blend) and write the folded mesh")
    p.add_argument("input", help="crease pattern: .svg, .fold or .blend")
    p.add_argument(
        "--out",
        required=True,
        help="output: .fold, .obj, .stl, .glb, .gltf or .blend (the folded mesh), or .svg (its flat crease pattern, as "
        "Export SVG writes it)",
    )
    p.add_argument(
        "--unit",
        default=None,
        choices=("mm", "m"),
        help="length unit of .stl/.obj output (default: millimetres for STL, metres for OBJ)",
    )
    p.add_argument("--angle", type=float, default=None, help="fold angle (deg, -180..180) for creases without one")
    p.add_argument("--percent", type=float, default=100.0, help="fold percent, 0–100 (default 100)")
    p.add_argument(
        "--interval",
        type=float,
        default=None,
        help="max chord length of discretised curves (an SVG's, or another tool's FOLD polylines), borders and "
        "cuts, and of straight creases split beside needle triangles (mm)",
    )
    p.add_argument("--tolerance", type=float, default=None, help="max curve deviation of a chord (mm)")
    p.add_argument("--mesh", default="ruling", choices=("ruling", "cdt", "earcut"), help="triangulation")
    p.add_argument("--solver", default="fast", choices=("fast", "faithful", "isometric"), help="solver method")
    p.add_argument("--report", default=None, help="write the report as JSON here")
    p.add_argument(
        "--collection",
        default=None,
        help="of a .blend input: fold this collection's crease curves (default: its scene's)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors (no summary, no progress)")
    p.add_argument(
        "--constraints",
        default=None,
        help="pins and glue as JSON (default: the .fold input's curved_fold:pins/glue, or <input>.constraints.json)",
    )
    p.set_defaults(func=run)


def _check_numbers(args: argparse.Namespace) -> None:
    """``--percent`` in [0, 100] and ``--angle`` in [−180, 180] degrees, both finite (150 % would set 270° targets);
    ``--interval`` and ``--tolerance`` positive millimetres."""
    if not (math.isfinite(args.percent) and 0.0 <= args.percent <= 100.0):
        raise PatternError(f"--percent {args.percent:g}: must be a number from 0 to 100")
    if args.angle is not None and not (math.isfinite(args.angle) and -180.0 <= args.angle <= 180.0):
        shown = f"{args.angle:.6g}" if math.isfinite(args.angle) else str(args.angle)
        raise PatternError(f"--angle {shown}: must be a number of degrees from -180 to 180")
    for name in ("interval", "tolerance"):  # as discretize checks them: a FOLD input ignored --tolerance nan
        value = getattr(args, name)
        if value is not None and not (value > 0 and math.isfinite(value)):
            raise PatternError(f"--{name} {value:g}: must be a positive number of mm")


def _last_error_line(exc: BaseException) -> str:
    """The informative line of an exporter's error: Blender wraps Python tracebacks in the message, whose last
    line (``OSError: [Errno 28] No space left on device``) says what happened."""
    lines = [x.strip() for x in str(exc).splitlines() if x.strip() and not x.strip().startswith("Location:")]
    return lines[-1] if lines else type(exc).__name__


class _Captured:
    failed = False


@contextlib.contextmanager
def _exporter_output(tmp: Path, out: Path, quiet: bool) -> Iterator[_Captured]:
    """Catch what Blender's exporters print on file descriptors 1 and 2 (they name the temporary file, and a
    failing glTF export prints a whole traceback): on success its warnings and errors are passed on with the
    user's path in place of the temporary one (:func:`_worth_passing_on`), the rest is progress chatter and
    dropped; on failure it is dropped, the one-line error says what happened."""
    import sys
    import tempfile

    log = _Captured()
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 1)
        os.dup2(sink.fileno(), 2)
        try:
            yield log
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            if not log.failed and not quiet:
                sink.seek(0)
                try:
                    text = _worth_passing_on(sink.read().decode("utf-8", "replace"))
                    sys.stdout.write(_user_paths(text, tmp, out))
                    sys.stdout.flush()
                except BrokenPipeError:  # no one reads the output any more (`| head -1`): the write goes on
                    stdout_to_devnull()


def _worth_passing_on(text: str) -> str:
    """The lines of an exporter's output that say something went wrong (a warning or an error). The rest is
    progress chatter that came before the fold's own summary: five lines from the glTF exporter ("INFO Draco mesh
    compression is available …", "06:53:11 | INFO: Starting glTF 2.0 export", …), "Writing to …" and "Info: File
    exported successfully" from OBJ and STL, "Timer 'STL Export' took 0.14 ms"; and bpy 5.2's glTF exporter's
    "ERROR Draco is not available because library could not be found …" (an optional compression library)."""
    import re

    keep = re.compile(r"warning|error|fail", re.IGNORECASE)  # RuntimeWarning, KeyError, 2 warnings too
    optional = re.compile(r"(Draco|MeshOptimizer)\b.*\bavailable\b")  # bpy 5.2's glTF: optional libraries
    lines = text.splitlines(keepends=True)
    return "".join(line for line in lines if keep.search(line) and not optional.search(line))


def _user_paths(text: str, tmp: Path, out: Path) -> str:
    """``text`` with the temporary files of a write named as the user's ``out``: ``tmp`` itself and the exporter's
    own temporary file beside it (``scene.export`` writes atomically too, to ``.<tmp stem>.<random>.tmp<suffix>``,
    which Blender's OBJ writer prints as "Writing to …")."""
    import re

    inner = re.escape("." + tmp.stem + ".") + r"[\w-]+" + re.escape(".tmp" + tmp.suffix)
    text = re.sub(re.escape(str(tmp.parent) + os.sep) + inner, lambda _m: str(out), text)
    text = re.sub(inner, lambda _m: out.name, text)
    return text.replace(str(tmp), str(out)).replace(tmp.name, out.name)


def _write_mesh(tmp: Path, out: Path, fold, quiet: bool = False, unit: str | None = None) -> None:
    """Write the folded mesh to the temporary path ``tmp`` in the format of ``out``'s suffix (``unit``: of STL/OBJ,
    ``"mm"`` or ``"m"``; their defaults otherwise)."""
    if out.suffix.lower() == ".fold":
        from ..core.io.fold import write_folded_fold

        write_folded_fold(tmp, fold.mesh, [fold.result.positions], [fold.result.fold_angles])
        return
    if out.suffix.lower() == ".svg":  # the flat crease pattern, as Blender's Export SVG writes it from the fold
        try:
            from ..scene.export import write_pattern_svg
        except ImportError as exc:  # pragma: no cover - depends on the Blender side being installed
            raise PatternError(f"--out {out}: .svg output needs Blender's bpy ({exc})") from exc
        write_pattern_svg(tmp, fold.mesh)
        return
    try:
        from ..scene.export import check_complete, export_folded_file
    except ImportError as exc:  # pragma: no cover - depends on the Blender side being installed
        raise PatternError(f"--out {out}: {out.suffix} output needs Blender's bpy ({exc})") from exc
    with _exporter_output(tmp, out, quiet) as log:
        try:
            export_folded_file(tmp, fold.mesh, fold.result.positions, fold_angles=fold.result.fold_angles, unit=unit)
        except (RuntimeError, OSError) as exc:  # Blender operators raise RuntimeError("Error: ..."), .blend OSError
            log.failed = True
            if _last_error_line(exc).startswith("KeyboardInterrupt"):  # Ctrl-C inside the exporter: interrupted
                raise KeyboardInterrupt from None
            raise OutputError(f"--out {out}: Blender's {out.suffix} exporter failed: {_last_error_line(exc)}") from None
    try:
        check_complete(tmp, out.suffix, fold.mesh.n_vertices)
    except OSError as exc:
        raise OutputError(f"--out {out}: {exc}; the old file (if any) is kept") from None


def _convergence(report: dict) -> str:
    """How the run ended, for the summary line: "converged", "converged to round-off" (the residual is above the
    tolerance, but no representable position is measurably closer: the report's ``converged_to_round_off``), or
    "NOT converged"."""
    if not report["converged"]:
        return "NOT converged"
    return "converged to round-off" if report.get("converged_to_round_off") else "converged"


def run(args: argparse.Namespace) -> int:
    from ..core.io.constraints_file import read_constraints
    from ..core.io.reader import read_pattern
    from ..core.pipeline import fold_pattern

    out = Path(args.out)
    if out.suffix.lower() not in OUTPUT_SUFFIXES:
        raise PatternError(f"--out {out}: unknown output type {out.suffix!r}; use one of {', '.join(OUTPUT_SUFFIXES)}")
    _check_numbers(args)
    if args.unit is not None and out.suffix.lower() not in (".stl", ".obj"):
        raise PatternError(f"--unit {args.unit}: only .stl and .obj outputs have a choice of unit (glTF is metres)")
    check_outputs(args.input, {"--out": out, "--report": args.report})
    progress = Progress(quiet=args.quiet)
    with progress.stage(Path(args.input).name):
        pattern = read_pattern(args.input, interval=args.interval, tolerance=args.tolerance, collection=args.collection)
        held = read_constraints(args.input, args.constraints)
    with progress.stage(f"folding {pattern.n_edges:,} segments"):
        fold = fold_pattern(
            pattern,
            angle=args.angle,
            percent=args.percent / 100.0,
            mesh_type=args.mesh,
            solver=args.solver,
            constraints=held,
        )
    r = fold.report
    # both files or neither: the report is moved into place first, and if that fails the mesh is not written
    with atomic_output(out) as tmp_out, contextlib.ExitStack() as stack:
        _write_mesh(tmp_out, out, fold, args.quiet, args.unit)
        if args.report:
            tmp_report = stack.enter_context(atomic_output(args.report))
            text = json.dumps(finite_json(r), indent=2, allow_nan=False)
            tmp_report.write_text(text + "\n", encoding="utf-8")
    if args.quiet:
        return 0
    print(
        f"{args.input}: {r['faces']} faces ({r['mesh_type']}, {r['generation_ms']:.0f} ms), "
        f"{r['solver']} solver {r['simulation_ms']:.0f} ms ({r['simulation_cpu_ms']:.0f} ms CPU), "
        f"{r['iterations']} iterations, "
        f"{_convergence(r)} (residual {r['residual']:.1e})"
    )
    # None (nan) when no panel edge bends the authors' 0.5°: at 0 %, rigid panels, or panels bent smoothly over
    # many edges, each less (a designer's strips rolled into cylinders: "panels flat" was not true there)
    warp = r["warp_mean_deg"]
    warp_text = (
        f"warp mean {warp:.2f}°"
        if warp is not None and math.isfinite(warp)
        else "no warp measured (no panel edge bends 0.5° or more)"
    )
    print(
        f"strain mean {r['strain_mean_pct']:.3f} % max {r['strain_max_pct']:.3f} %, {warp_text}, "
        f"fold-angle error {r['fold_angle_error_mean_deg']:.2f}° → {out}"
    )
    crossing = r.get("self_intersecting_faces")
    if crossing is not None:
        print(
            f"self-intersection: {crossing} faces pass through the sheet elsewhere"
            if crossing
            else "self-intersection: none (no face passes through another)"
        )
    if r.get("pins") or r.get("glue"):
        line = f"pins {r['pins']}" + (f" (max {r['pin_error_max_mm']:.1e} mm off target)" if r["pins"] else "")
        if r["glue"]:
            line += f", glue {r['glue']} (max gap {r['glue_gap_max_mm']:.2e} mm = {r['glue_gap_rel']:.1e} of diagonal)"
        print(line)
    if r.get("does_not_fold_as_assigned"):
        print("warning: " + r["does_not_fold_message"])
    for w in r.get("warnings", [])[:5]:
        print("warning: " + str(w))
    return 0
