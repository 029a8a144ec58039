"""Scaling with mesh size (issue 6, part 3): time per solver iteration, time to converge and peak memory against
the number of faces, from ~150 to ~20,000, with fitted exponents.

The pattern family is the one of ``tests/test_robust_hard_cases.py::test_twenty_thousand_faces``: a 100 mm square
with ``n`` wavy pleats (cubic Béziers, alternating valley +20° / mountain −20°), discretised at a shrinking
interval, folded at 100 % with the ruling mesh. Small fold angles keep every size in the same regime (a few Newton
iterations), so the exponents describe the cost of one iteration rather than a change of difficulty.

Measured per size: generation ms; fast solver iterations, wall ms to the 1e-6 residual and ms per iteration;
faithful solver ms per step (a short capped run: it needs 10⁴–10⁵ steps to converge, see docs/solver.md, so its
time to converge is not measured here); peak memory (tracemalloc) of the mesh generation, of a fast solve capped at
two iterations (the first Hessian assembly and factorisation dominate) and of a short faithful run.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from curved_fold.core.mesh.build import build_mesh
from curved_fold.core.pattern.discretize import discretize
from curved_fold.core.pattern.model import CreaseCurve, CreasePattern, CurveSegment
from curved_fold.core.solve.solver import Solver, SolverSettings

from .common import IMG, fit_exponent, peak_memory

SIZES = ((3, 10.0), (8, 4.0), (12, 2.5), (16, 1.6), (24, 0.8), (28, 0.5), (30, 0.3))
"""(pleats, interval mm): about 150, 500, 1,100, 2,200, 6,500, 11,000 and 21,000 faces."""


def pleats_pattern(n: int, interval: float, size: float = 100.0) -> CreasePattern:
    """``n`` wavy pleats across a ``size`` mm square, alternating V +20° / M −20°, discretised at ``interval``."""

    def line(a, b) -> CurveSegment:
        return CurveSegment("line", np.array([a, b], dtype=float))

    c = [(0, 0), (size, 0), (size, size), (0, size)]
    curves = [CreaseCurve([line(c[i], c[(i + 1) % 4]) for i in range(4)], "B", None, closed=True, source="border")]
    for k in range(n):
        x, a = size * (k + 1) / (n + 1), 0.3 * size / (n + 1)
        role, angle = ("M", -20.0) if k % 2 else ("V", 20.0)
        pts = np.array([(x, 0), (x + a, size / 3), (x - a, 2 * size / 3), (x, size)], dtype=float)
        curves.append(CreaseCurve([CurveSegment("cubic", pts)], role, angle, source=f"pleat {k}"))
    return discretize(curves, interval=interval)


def measure_size(n: int, interval: float, *, fast_seconds: float = 90.0, faithful_steps: int = 200) -> dict[str, Any]:
    """One size of the family: the figures listed in the module docstring."""
    pattern = pleats_pattern(n, interval)
    t0 = time.perf_counter()
    mesh = build_mesh(pattern, "ruling")
    gen_ms = (time.perf_counter() - t0) * 1000.0
    row: dict[str, Any] = {"pleats": n, "interval": interval, "faces": mesh.n_faces, "nodes": mesh.n_vertices}
    row["gen_ms"] = gen_ms
    _, row["gen_peak_mib"] = peak_memory(lambda: build_mesh(pattern, "ruling"))

    fast = Solver(mesh, SolverSettings(time_limit=fast_seconds), "fast")
    t0 = time.perf_counter()
    r = fast.solve(1.0)
    row["fast_ms"] = (time.perf_counter() - t0) * 1000.0
    row.update(
        fast_iterations=r.iterations,
        fast_converged=r.converged,
        fast_residual=r.residual,
        fast_assemblies=r.hessian_assemblies,
        fast_ms_per_iteration=row["fast_ms"] / max(r.iterations, 1),
    )
    capped = Solver(mesh, SolverSettings(max_iterations=2), "fast")
    _, row["fast_peak_mib"] = peak_memory(lambda: capped.solve(1.0))

    slow = Solver(mesh, SolverSettings(max_steps=faithful_steps), "faithful")
    _ = slow.dt  # the time step (power iteration) is set-up, not stepping: keep it out of the per-step figure
    t0 = time.perf_counter()
    s = slow.solve(1.0, stop_on_convergence=False)
    row["faithful_ms_per_step"] = (time.perf_counter() - t0) * 1000.0 / max(s.iterations, 1)
    row["faithful_steps"] = s.iterations
    _, row["faithful_peak_mib"] = peak_memory(lambda: slow.solve(1.0, max_steps=20, stop_on_convergence=False))
    return row


def run_scaling(budget_s: float, sizes=SIZES, echo: bool = True, always: int = 1) -> dict[str, Any]:
    """Measure the sizes in increasing order; a size is skipped (and reported) when the time left is less than the
    previous size took × its face ratio (the cost grows about linearly or faster). The first ``always`` sizes are
    measured whatever the budget (the quick smoke run needs two points for a fit, also on a busy machine)."""
    rows: list[dict[str, Any]] = []
    skipped: list[str] = []
    t_start = time.perf_counter()
    last_s, last_faces = 0.0, 0
    for n, interval in sizes:
        left = budget_s - (time.perf_counter() - t_start)
        expected_faces = 2.0 * (n + 4) * 100.0 / interval
        if len(rows) >= always and last_s * expected_faces / max(last_faces, 1) > left:
            skipped.append(f"{n} pleats at {interval} mm (~{expected_faces:.0f} faces): budget left {left:.0f} s")
            continue
        t0 = time.perf_counter()
        try:
            row = measure_size(n, interval, fast_seconds=max(min(left / 2, 90.0), 5.0))
        except Exception as exc:  # reported, not hidden
            row = {"pleats": n, "interval": interval, "error": f"{type(exc).__name__}: {exc}"}
        last_s, last_faces = time.perf_counter() - t0, row.get("faces", last_faces)
        rows.append(row)
        if echo and "error" not in row:
            print(
                f"  scaling {row['faces']} faces: gen {row['gen_ms']:.0f} ms, fast {row['fast_ms']:.0f} ms "
                f"({row['fast_iterations']} it, {row['fast_ms_per_iteration']:.1f} ms/it), faithful "
                f"{row['faithful_ms_per_step']:.2f} ms/step, peak {row['fast_peak_mib']:.1f} MiB ({last_s:.0f} s)",
                flush=True,
            )
        elif echo:
            print(f"  scaling {n} pleats: {row['error']}", flush=True)
    ok = [r for r in rows if "error" not in r]
    faces = [r["faces"] for r in ok]
    fits = {
        key: fit_exponent(faces, [r[key] for r in ok])
        for key in (
            "gen_ms",
            "fast_ms_per_iteration",
            "fast_ms",
            "faithful_ms_per_step",
            "gen_peak_mib",
            "fast_peak_mib",
            "faithful_peak_mib",
        )
    }
    return {"rows": rows, "fits": fits, "skipped": skipped, "seconds": time.perf_counter() - t_start}


LABELS = {
    "gen_ms": "generation ms",
    "fast_ms_per_iteration": "fast: ms per Newton iteration",
    "fast_ms": "fast: ms to converge",
    "faithful_ms_per_step": "faithful: ms per step",
    "gen_peak_mib": "generation peak MiB",
    "fast_peak_mib": "fast solve peak MiB",
    "faithful_peak_mib": "faithful peak MiB",
}


def plot(scaling: dict[str, Any], img_dir: Path = IMG) -> list[str]:
    """``docs/img/bench_scaling.png``: times (left) and peak memory (right) against #faces, log-log, fitted lines."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    img_dir.mkdir(parents=True, exist_ok=True)
    ok = [r for r in scaling["rows"] if "error" not in r]
    if not ok:
        return []
    faces = np.array([r["faces"] for r in ok], dtype=float)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    groups = (
        (axes[0], ("fast_ms", "fast_ms_per_iteration", "faithful_ms_per_step", "gen_ms"), "wall ms"),
        (axes[1], ("fast_peak_mib", "faithful_peak_mib", "gen_peak_mib"), "peak traced memory (MiB)"),
    )
    xs = np.geomspace(faces.min(), faces.max(), 20)
    for ax, keys, ylabel in groups:
        for key in keys:
            y = np.array([r[key] for r in ok], dtype=float)
            slope, err = scaling["fits"][key]
            (line,) = ax.plot(faces, y, "o", label=f"{LABELS[key]}: ∝ F^{slope:.2f}±{err:.2f}")
            if np.isfinite(slope):
                ok_y = y > 0
                c = np.exp(np.mean(np.log(y[ok_y]) - slope * np.log(faces[ok_y])))
                ax.plot(xs, c * xs**slope, "-", color=line.get_color(), lw=0.8, alpha=0.7)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("faces (triangles)")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Scaling on wavy pleats (100 mm square, ±20°, ruling mesh, 100 %)")
    fig.tight_layout()
    p = img_dir / "bench_scaling.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    return [p.name]
