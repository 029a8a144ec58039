"""Fast vs faithful solver benchmark over the Origami Simulator fixtures and the examples (issue 4).

For every case: both solvers' iterations, force evaluations, wall ms, residual and energy, the RMS difference of
their shapes after rigid (Kabsch) alignment ÷ the sheet diagonal, the strain, and the isometric solver's strain.
The faithful run is capped (seconds) and reports the residual it reached where capped. Results are printed as a
table and written into the generated section of ``docs/solver.md``.

Run: ``.venv/bin/python -m curved_fold.benchmarks.solvers [--quick] [--no-write]`` (or as a script).
``--tail`` instead compares the solver with and without its tail, saddle handling and continuation (issue 12):
:func:`run_tail_case` per fixture and example at 60 % and 100 %, plus :func:`run_frames` (per-frame CPU), written into
its own generated section of ``docs/solver.md``.
Functions for other tools (``make bench``): :func:`run_case`, :func:`run_all`, :func:`format_table`,
:func:`write_docs`.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

if __package__ in (None, ""):  # run as a script: make the add-on importable as ``curved_fold``
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
    __package__ = "curved_fold.benchmarks"

from curved_fold.benchmarks.common import replace_section  # noqa: E402
from curved_fold.core.io.reader import read_pattern  # noqa: E402
from curved_fold.core.mesh.build import build_mesh  # noqa: E402
from curved_fold.core.pattern.model import CreasePattern  # noqa: E402
from curved_fold.core.solve.solver import Solver, SolverSettings, rigid_rms  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
FIXTURES = REPO / "tests" / "fixtures" / "origami-simulator"
EXAMPLES = REPO / "examples"
DOC = REPO / "docs" / "solver.md"
BEGIN, END = "<!-- BEGIN GENERATED: benchmarks/solvers.py -->", "<!-- END GENERATED: benchmarks/solvers.py -->"
TAIL_BEGIN = "<!-- BEGIN GENERATED: benchmarks/solvers.py --tail -->"
TAIL_END = "<!-- END GENERATED: benchmarks/solvers.py --tail -->"

BIG = ("shell14.svg", "CircularPleat-antiFacet.svg", "huffmanTower.svg", "Rotating_Star.svg", "Carved_Cylinder.svg")
"""Fixtures where the faithful model would run for minutes: capped shorter in the benchmark."""


def _strain_mean_pct(mesh, positions: np.ndarray) -> float:
    from curved_fold.core.metrics.measures import summary

    return float(summary(mesh, positions)["strain_mean_pct"])


def run_case(
    source: str | Path | CreasePattern,
    percent: float = 0.6,
    *,
    mesh_type: str = "ruling",
    faithful_seconds: float = 20.0,
    faithful_min_ratio: float = 3.0,
    faithful: bool = True,
    isometric: bool = True,
    tolerance: float = 1e-6,
) -> dict[str, Any]:
    """Fold one pattern with the fast, faithful (capped) and isometric solvers; return the figures as a dict.

    ``source`` is a path (.svg/.fold/.blend) or a pattern; ``percent`` is 1.0 for 100 %. All solvers start from the
    same (flat) state and use the same scale-free residual criterion ``tolerance``. The faithful cap is
    ``max(faithful_seconds, faithful_min_ratio × fast wall time)``, so a capped faithful row always had at least
    ``faithful_min_ratio`` times the fast solver's time.
    """
    name = Path(source).name if not isinstance(source, CreasePattern) else "pattern"
    pattern = read_pattern(source) if not isinstance(source, CreasePattern) else source
    mesh = build_mesh(pattern, mesh_type=mesh_type)
    diag = float(mesh.diagonal)
    row: dict[str, Any] = {"case": name, "percent": percent, "faces": int(mesh.n_faces), "nodes": mesh.n_vertices}
    settings = SolverSettings(tolerance=tolerance)
    fast_solver = Solver(mesh, settings, "fast")
    t0 = time.perf_counter()
    fast = fast_solver.solve(percent)
    row.update(
        fast_ms=(time.perf_counter() - t0) * 1000.0,
        fast_iterations=fast.iterations,
        fast_force_evaluations=fast.force_evaluations,
        fast_assemblies=fast.hessian_assemblies,
        fast_linear_solves=fast.linear_solves,
        fast_converged=fast.converged,
        fast_residual=fast.residual,
        fast_energy=fast.energy,
        fast_strain_pct=_strain_mean_pct(mesh, fast.positions),
    )
    if faithful:
        cap = max(faithful_seconds, faithful_min_ratio * row["fast_ms"] / 1000.0)
        slow_settings = SolverSettings(tolerance=tolerance, time_limit=cap, max_steps=10_000_000)
        t0 = time.perf_counter()
        slow = Solver(mesh, slow_settings, "faithful").solve(percent)
        row.update(
            faithful_ms=(time.perf_counter() - t0) * 1000.0,
            faithful_steps=slow.iterations,
            faithful_force_evaluations=slow.force_evaluations,
            faithful_converged=slow.converged,
            faithful_residual=slow.residual,
            faithful_energy=slow.energy,
            faithful_dt=slow.dt,
            rms_over_diagonal=rigid_rms(fast.positions, slow.positions) / diag,
        )
        # which equilibrium was the faithful run heading to? Newton from its last state finds the basin's minimum
        basin = fast_solver.solve(percent, start=slow.positions, theta_prev=slow.theta)
        row["basin_energy"] = basin.energy
        row["basin_rms_over_diagonal"] = rigid_rms(fast.positions, basin.positions) / diag
        row["same_state"] = bool(row["basin_rms_over_diagonal"] <= 1e-3)
        row["wall_ratio"] = row["faithful_ms"] / max(row["fast_ms"], 1e-9)
        row["evaluation_ratio"] = row["faithful_force_evaluations"] / max(row["fast_force_evaluations"], 1)
        lower = "fast" if fast.energy < slow.energy - 1e-9 * max(abs(slow.energy), 1.0) else "same/faithful"
        row["lower_energy"] = lower
    if isometric:
        t0 = time.perf_counter()
        iso = Solver(mesh, SolverSettings(tolerance=tolerance, max_iterations=300), "isometric").solve(percent)
        row.update(
            isometric_ms=(time.perf_counter() - t0) * 1000.0,
            isometric_iterations=iso.iterations,
            isometric_converged=iso.converged,
            isometric_residual=iso.residual,
            isometric_strain_pct=_strain_mean_pct(mesh, iso.positions),
        )
    return row


SETTLES = ("miura-ori.svg", "curved_border.svg", "single_curve.svg", "concentric_arcs.svg", "curved_pleats.svg")
"""Cases where the faithful model settles within about a minute here: given a longer cap to show agreement."""


def cases(quick: bool = False) -> list[tuple[Path, float, float]]:
    """(path, percent, faithful cap in seconds): every fixture and example at 60 %, three fixtures also at 100 %.

    Caps keep the whole run near 8 minutes on 2 shared cores: 45 s where the faithful model settles (``SETTLES``),
    6 s on the big fixtures (``BIG``), 15 s elsewhere; capped rows report the residual reached.
    """
    out: list[tuple[Path, float, float]] = []
    fixtures = sorted(FIXTURES.glob("*.svg")) if FIXTURES.is_dir() else []
    examples = sorted(EXAMPLES.glob("*.svg"))
    for path in fixtures + examples:
        big = path.name in BIG
        if quick and (big or path in examples):
            continue
        out.append((path, 0.6, 6.0 if big else 45.0 if path.name in SETTLES else 15.0))
    for name in ("simpleVertex.svg", "curvedPleatSimple.svg", "miura-ori.svg"):
        if (FIXTURES / name).exists() and not quick:
            out.append((FIXTURES / name, 1.0, 15.0))
    return out


def run_frames(cells: int = 32, frames: int = 60) -> dict[str, Any]:
    """Quasi-static animation on a ``cells × cells`` grid (2·cells² faces) with a straight 120° valley, fold percent
    stepping by 1/``frames`` per frame: median/max wall ms per frame, CPU ms, Newton iterations, factorisations."""
    from curved_fold.core.solve.animation import FoldAnimation
    from curved_fold.core.solve.model import mesh_from_triangles

    n = cells
    g = np.array([[i, j] for j in range(n + 1) for i in range(n + 1)], float) * 200.0 / n
    tris = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            tris += [[a, a + 1, a + n + 2], [a, a + n + 2, a + n + 1]]
    creases = {(n // 2 + j * (n + 1), n // 2 + (j + 1) * (n + 1)): ("V", 120.0) for j in range(n)}
    mesh = mesh_from_triangles(g, np.array(tris), creases)
    anim = FoldAnimation(mesh, SolverSettings())
    wall, cpu, its, conv = [], [], [], []
    for k in range(1, frames + 1):
        c0 = time.process_time()
        f = anim.frame(k / frames)
        cpu.append((time.process_time() - c0) * 1000.0)
        wall.append(f.ms)
        its.append(f.iterations)
        conv.append(f.converged)
    return {
        "faces": int(mesh.n_faces),
        "frames": frames,
        "median_ms": float(np.median(wall)),
        "max_ms": float(np.max(wall)),
        "median_cpu_ms": float(np.median(cpu)),
        "median_iterations": float(np.median(its)),
        "factorisations": int(anim.solver.assembler.assemblies),
        "all_converged": bool(all(conv)),
    }


def run_tail_case(path: Path, percent: float) -> dict[str, Any]:
    """One pattern at ``percent``: the previous solver (Gauss–Newton only, one solve from the flat sheet:
    ``exact_tail=False, continuation=False``) beside the current one (exact tail, saddle escapes, continuation), with
    CPU seconds (``time.process_time``), iterations, residual, energy, the current run's exact iterations, saddle
    escapes and negative pivots at the end, and the RMS/diagonal between the static fold and the last frame of a
    0 → percent animation in 7 frames."""
    from curved_fold.core.solve.animation import FoldAnimation

    mesh = build_mesh(read_pattern(path), mesh_type="ruling")
    row: dict[str, Any] = {"case": path.name, "percent": percent, "faces": int(mesh.n_faces)}
    for key, settings, continuation in (
        ("old", SolverSettings(exact_tail=False), False),
        ("new", SolverSettings(), True),
    ):
        c0 = time.process_time()
        r = Solver(mesh, settings).solve(percent, continuation=continuation)
        row[f"{key}_cpu_s"] = time.process_time() - c0
        row[f"{key}_it"] = r.iterations
        row[f"{key}_res"] = r.residual
        row[f"{key}_conv"] = r.converged
        row[f"{key}_energy"] = r.energy
        if key == "new":
            row.update(exact=r.exact_iterations, saddles=r.saddle_escapes, neg=r.negative_pivots)
            static = r.positions
    anim = FoldAnimation(mesh, SolverSettings())
    for k in range(1, 8):
        last = anim.frame(percent * k / 7)
    row["anim_rms_diag"] = rigid_rms(static, last.positions) / mesh.diagonal
    return row


TAIL_COLUMNS = (
    ("case", "case", "s"),
    ("%", "percent", "%"),
    ("faces", "faces", "d"),
    ("old it", "old_it", "d"),
    ("old CPU s", "old_cpu_s", ".2f"),
    ("old res", "old_res", ".1e"),
    ("old E", "old_energy", ".6g"),
    ("new it", "new_it", "d"),
    ("exact it", "exact", "d"),
    ("saddle steps", "saddles", "d"),
    ("new CPU s", "new_cpu_s", ".2f"),
    ("new res", "new_res", ".1e"),
    ("new E", "new_energy", ".6g"),
    ("neg. pivots", "neg", "d"),
    ("static vs anim RMS/diag", "anim_rms_diag", ".1e"),
)


def format_tail_table(rows: list[dict[str, Any]], header: bool = True) -> str:
    """Markdown table of :func:`run_tail_case` rows."""
    out = []
    if header:
        out.append("| " + " | ".join(c[0] for c in TAIL_COLUMNS) + " |")
        out.append("|" + "---|" * len(TAIL_COLUMNS))
    for row in rows:
        if "error" in row:
            out.append(f"| {row['case']} | {row['percent']:.0%} | error: {row['error']} |")
            continue
        cells = []
        for _, key, spec in TAIL_COLUMNS:
            v = row.get(key)
            cells.append(f"{v:.0%}" if spec == "%" else _fmt(v, spec))
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def run_tail(quick: bool = False) -> tuple[list[dict[str, Any]], list[str]]:
    """:func:`run_tail_case` over every fixture and example at 60 % and 100 %, and the per-frame benchmark."""
    rows = []
    paths = sorted(FIXTURES.glob("*.svg")) + sorted(EXAMPLES.glob("*.svg"))
    if quick:
        paths = [p for p in paths if p.name not in BIG + ("Treble_Clef.svg",)]
    for path in paths:
        for percent in (0.6, 1.0):
            try:
                row = run_tail_case(path, percent)
            except Exception as exc:  # a failing case is reported, not hidden
                row = {"case": path.name, "percent": percent, "error": f"{type(exc).__name__}: {exc}"}
            rows.append(row)
            print(format_tail_table([row], header=len(rows) == 1), flush=True)
    ok = [r for r in rows if "error" not in r]
    frames = run_frames(cells=32, frames=60)
    lines = [
        f"- converged: previous {sum(r['old_conv'] for r in ok)}/{len(rows)}, current {sum(r['new_conv'] for r in ok)}"
        f"/{len(rows)}; CPU total previous {sum(r['old_cpu_s'] for r in ok):.1f} s, current "
        f"{sum(r['new_cpu_s'] for r in ok):.1f} s",
        f"- static fold vs last animation frame: max RMS/diag {max((r['anim_rms_diag'] for r in ok), default=0):.1e}",
        f"- runs that stepped out of a saddle: {sum(1 for r in ok if r['saddles'])}; runs using the exact tail: "
        f"{sum(1 for r in ok if r['exact'])}/{len(ok)}",
        f"- quasi-static animation, {frames['faces']} faces, percent +1/{frames['frames']} per frame: median "
        f"{frames['median_cpu_ms']:.0f} ms CPU per frame ({frames['median_ms']:.0f} ms wall), "
        f"{frames['median_iterations']:.0f} Newton iterations, {frames['factorisations']} factorisations in "
        f"{frames['frames']} frames, all converged: {frames['all_converged']}",
    ]
    return rows, lines


def write_tail_docs(rows: list[dict[str, Any]], lines: list[str], path: Path = DOC) -> None:
    """Replace the ``--tail`` generated section of ``docs/solver.md`` (appended if its markers are absent)."""
    body = "\n".join(
        [
            TAIL_BEGIN,
            f"Generated by `benchmarks/solvers.py --tail` on {time.strftime('%Y-%m-%d %H:%M')}. "
            f"Machine: {machine_line()}.",
            "Ruling mesh, tolerance 1e-6. *old* = the previous solver (Gauss–Newton only, one solve from the flat "
            "sheet; its steps stretched as today's are); *new* = exact tail + saddle escapes + continuation. CPU "
            "seconds by `time.process_time`.",
            "",
            format_tail_table(rows),
            "",
            *lines,
            TAIL_END,
        ]
    )
    replace_section(path, TAIL_BEGIN, TAIL_END, body)


def run_all(quick: bool = False, echo: bool = True) -> list[dict[str, Any]]:
    """Run :func:`run_case` over :func:`cases`; rows print as they finish when ``echo``."""
    rows = []
    for path, percent, cap in cases(quick):
        try:
            row = run_case(path, percent, faithful_seconds=cap)
        except Exception as exc:  # a failing case is reported, not hidden
            row = {"case": path.name, "percent": percent, "error": f"{type(exc).__name__}: {exc}"}
        rows.append(row)
        if echo:
            print(format_table([row], header=not rows[:-1]), flush=True)
    return rows


def _fmt(v: Any, spec: str) -> str:
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    return format(v, spec)


def format_table(rows: list[dict[str, Any]], header: bool = True) -> str:
    """Markdown table of benchmark rows."""
    cols = [
        ("case", "case", "s"),
        ("%", "percent", ".0%"),
        ("faces", "faces", "d"),
        ("fast it", "fast_iterations", "d"),
        ("fast evals", "fast_force_evaluations", "d"),
        ("fast asm", "fast_assemblies", "d"),
        ("fast ms", "fast_ms", ".0f"),
        ("fast res", "fast_residual", ".1e"),
        ("faithful steps", "faithful_steps", "d"),
        ("faithful ms", "faithful_ms", ".0f"),
        ("faithful res", "faithful_residual", ".1e"),
        ("faithful conv", "faithful_converged", ""),
        ("RMS/diag", "rms_over_diagonal", ".1e"),
        ("E fast", "fast_energy", ".4g"),
        ("E faithful", "faithful_energy", ".4g"),
        ("same state", "same_state", ""),
        ("wall ×", "wall_ratio", ".0f"),
        ("evals ×", "evaluation_ratio", ".0f"),
        ("strain %", "fast_strain_pct", ".3f"),
        ("iso it", "isometric_iterations", "d"),
        ("iso strain %", "isometric_strain_pct", ".4f"),
    ]
    lines = []
    if header:
        lines.append("| " + " | ".join(c[0] for c in cols) + " |")
        lines.append("|" + "---|" * len(cols))
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['case']} | {r['percent']:.0%} | error: {r['error']} |")
            continue
        lines.append("| " + " | ".join(_fmt(r.get(key), spec) for _, key, spec in cols) + " |")
    return "\n".join(lines)


def summary_lines(rows: list[dict[str, Any]]) -> list[str]:
    """Min/median/max of the wall and evaluation ratios, agreement and isometric strain over the rows."""
    ok = [r for r in rows if "error" not in r and "wall_ratio" in r]
    out = []
    if ok:
        w = np.array([r["wall_ratio"] for r in ok])
        e = np.array([r["evaluation_ratio"] for r in ok])
        out.append(f"- wall ratio faithful/fast: min {w.min():.1f}×, median {np.median(w):.1f}×, max {w.max():.0f}×")
        out.append(f"- force-evaluation ratio: min {e.min():.0f}×, median {np.median(e):.0f}×, max {e.max():.0f}×")
        conv = [r for r in ok if r["faithful_converged"]]
        agree = [r for r in ok if r["rms_over_diagonal"] <= 1e-3]
        out.append(
            f"- faithful converged (residual ≤ tolerance) in {len(conv)}/{len(ok)} runs; RMS/diag ≤ 1e-3 in "
            f"{len(agree)}/{len(ok)} runs"
        )
        big = [r for r in ok if r["faithful_steps"] > 10_000]
        if big:
            out.append(
                f"- where the faithful model needed > 10,000 steps ({len(big)} runs): evaluation ratio min "
                f"{min(r['evaluation_ratio'] for r in big):.0f}×"
            )
    iso = [r for r in rows if "isometric_strain_pct" in r]
    if iso:
        s = np.array([r["isometric_strain_pct"] for r in iso])
        out.append(f"- isometric mean strain: max {s.max():.4f} % over {len(iso)} runs (target ≤ 0.05 %)")
    return out


def machine_line() -> str:
    """Machine and library versions for the report header."""
    try:
        cpu = next(
            (ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo") if ln.startswith("model name")), "unknown"
        )
    except OSError:
        cpu = platform.processor() or "unknown"
    return (
        f"{cpu}, {os.cpu_count()} cores (shared with other jobs while measured), {platform.system()} "
        f"{platform.release()}; Python {platform.python_version()}, numpy {np.__version__}"
    )


def write_docs(rows: list[dict[str, Any]], lines: list[str] | None = None, path: Path = DOC) -> None:
    """Replace the generated section of ``docs/solver.md`` with the table (appended if the markers are absent)."""
    body = "\n".join(
        [
            BEGIN,
            f"Generated by `benchmarks/solvers.py` on {time.strftime('%Y-%m-%d %H:%M')}. Machine: {machine_line()}.",
            "Ruling mesh; the faithful run is capped (seconds, see `cases()`); `RMS/diag` compares the fast and "
            "faithful shapes after rigid alignment; `evals` counts every model evaluation (line search included); "
            "`asm` Hessian assemblies+factorisations; `same state` = a Newton solve started from the faithful "
            "run's last state ends within 1e-3·diagonal of the fast solution (the faithful run was heading to the same "
            "equilibrium). Timings are wall-clock on a loaded machine.",
            "",
            format_table(rows),
            "",
            *(summary_lines(rows) if lines is None else lines),
            END,
        ]
    )
    replace_section(path, BEGIN, END, body)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small fixtures only")
    parser.add_argument("--no-write", action="store_true", help="do not update docs/solver.md")
    parser.add_argument("--json", default=None, help="also write the rows and summary lines as JSON here")
    parser.add_argument("--tail", action="store_true", help="previous vs current solver (tail, saddles, continuation)")
    args = parser.parse_args(argv)
    print(machine_line())
    if args.tail:
        rows, lines = run_tail(args.quick)
        print("\n".join(lines))
        if not args.no_write:
            write_tail_docs(rows, lines)
            print(f"wrote {DOC}")
        return 0
    rows = run_all(args.quick)
    frames = run_frames()
    lines = summary_lines(rows) + [
        f"- quasi-static animation, {frames['faces']} faces, percent +1/{frames['frames']} per frame: median "
        f"{frames['median_ms']:.0f} ms/frame wall ({frames['median_cpu_ms']:.0f} ms CPU), max {frames['max_ms']:.0f} "
        f"ms, {frames['median_iterations']:.0f} Newton iterations, {frames['factorisations']} factorisations in "
        f"{frames['frames']} frames, all converged: {frames['all_converged']}"
    ]
    print("\n".join(lines))
    if args.json:
        import json

        Path(args.json).write_text(json.dumps({"rows": rows, "lines": lines, "frames": frames}, indent=1, default=str))
    if not args.no_write:
        write_docs(rows, lines)
        print(f"wrote {DOC}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
