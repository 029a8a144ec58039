"""Curves → pattern → mesh → equilibrium, with the paper's report (paper §3–4, Table 1 columns).

:func:`fold_pattern` is what the CLI, the operators and the benchmarks call. It fills missing crease angles
(``angle``), builds the mesh (``core.mesh.build.build_mesh``), solves (``core.solve.solver``) and measures the result
with ``core.metrics.measures.summary``. :func:`refold_mesh` re-solves an already built mesh (the operators' re-fold
and live paths) and reports the same figures, including the "does not fold as assigned" verdict (paper Fig. 7).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .mesh.fold_mesh import FoldMesh
from .metrics.verdict import verdict
from .pattern.model import CreasePattern, PatternError
from .solve.constraints import Constraints, ConstraintSpec
from .solve.solver import FoldResult, Solver, SolverSettings


@dataclass
class FoldRun:
    """A folded pattern: the mesh, the solver result and a JSON-ready report dict."""

    mesh: FoldMesh
    result: FoldResult
    report: dict[str, Any]


def _with_angle(pattern: CreasePattern, angle: float | None) -> CreasePattern:
    if angle is None:
        return pattern
    if not np.isfinite(angle):
        raise PatternError(f"--angle must be a finite number of degrees, got {angle}")
    angles = pattern.fold_angles.astype(float).copy()
    assign = np.asarray(pattern.assignments)
    missing = np.isin(assign, ("M", "V")) & ~np.isfinite(angles)
    angles[missing & (assign == "V")] = abs(angle)
    angles[missing & (assign == "M")] = -abs(angle)
    return replace(pattern, fold_angles=angles)


def measure(mesh: FoldMesh, result: FoldResult, percent: float) -> dict[str, Any]:
    """Strain, warp, angle defect (``core.metrics.summary``) and the fold-angle error of the solver's own angles."""
    from .metrics import measures as metrics

    out: dict[str, Any] = dict(metrics.summary(mesh, result.positions, percent=percent))
    crease = mesh.is_crease()
    if np.any(crease):
        err = np.abs(result.fold_angles[crease] - percent * mesh.fold_angles[crease])
        # creases without two triangles have no simulated angle (nan): average the others, nan if there are none
        out["fold_angle_error_mean_deg"] = float(np.nanmean(err)) if np.any(np.isfinite(err)) else float("nan")
    else:
        out["fold_angle_error_mean_deg"] = 0.0
    return out


def self_intersecting_faces(mesh: FoldMesh, positions: np.ndarray, crossing: np.ndarray | None = None) -> int | None:
    """Triangles passing through a non-adjacent triangle (``core.metrics.intersections``); None if not finite.
    ``crossing``: the per-triangle mask if the caller already has it (a Blender job measures it in a unit of its
    own and colours the faces with it)."""
    from .metrics.intersections import count_intersecting_faces

    positions = np.asarray(positions, dtype=np.float64)
    if not np.all(np.isfinite(positions)):
        return None
    if crossing is not None:
        return int(np.count_nonzero(crossing))
    return count_intersecting_faces(positions, mesh.triangles)


def state_report(result: FoldResult) -> dict[str, Any]:
    """Which equilibrium was reached: its energy, whether it is a stable minimum (no negative pivot of the exact
    Hessian), and where along the folding path another state branches off (a saddle the solver stepped out of). An
    unconverged state is no equilibrium, whatever its pivots (a designer's spiral stopped at the iteration cap with
    residual 1.8e-3 read "stable minimum")."""
    n = result.negative_pivots
    if not result.converged:  # a stopped solve is on its way somewhere: its pivots say nothing of an equilibrium
        state = f"not an equilibrium: the solve stopped before it converged (energy {result.energy:.6g})"
    elif n is None:
        state = "not measured"
    elif n == 0:
        state = f"stable minimum (energy {result.energy:.6g})"
    else:
        state = f"saddle with {n} negative curvature direction{'s' if n > 1 else ''} (energy {result.energy:.6g})"
    out: dict[str, Any] = {"state": state, "negative_pivots": n}
    if result.saddle_percents:
        where = ", ".join(f"{100 * p:.0f} %" for p in result.saddle_percents)
        out["other_state_near"] = (
            f"the folding path passed a saddle near {where}: another equilibrium branches off there "
            "(the fold followed the lower side)"
        )
    return out


def _flat_crease_warning(mesh: FoldMesh) -> list[str]:
    """A warning naming the mountains and valleys whose fold angle is 0°: they stay flat, and a fold of nothing else
    "converged" without a word (a designer session's Fold Angle left at 0 in Blender)."""
    flat = np.isin(mesh.assignments, ("M", "V")) & (mesh.fold_angles == 0.0)
    if not flat.any():
        return []
    polys = [int(k) for k in dict.fromkeys(mesh.edge_polyline[flat].tolist()) if 0 <= k < len(mesh.sources)]
    names = ", ".join(mesh.sources[k] for k in polys[:4]) + (f" and {len(polys) - 4} more" if len(polys) > 4 else "")
    return [
        f"{len(polys) or int(flat.sum())} mountain/valley crease(s) with a fold angle of 0° stay flat"
        + (f": {names}" if names else "")
        + "; give them a fold angle (Fold Angle in Blender, opacity in SVG, edges_foldAngle in FOLD)"
    ]


def make_report(
    mesh: FoldMesh,
    result: FoldResult,
    percent: float,
    *,
    mesh_type: str,
    solver: str,
    warnings: list[str],
    constraints: Constraints | None = None,
    start: np.ndarray | None = None,
    crossing: np.ndarray | None = None,
) -> dict[str, Any]:
    """The JSON-ready report of one solve: sizes, timings, solver counts, metrics and the Fig. 7 verdict
    (``crossing``: the self-intersection mask per triangle, when already measured)."""
    report: dict[str, Any] = {
        "vertices": int(mesh.n_vertices),
        "faces": int(mesh.n_faces),
        "mesh_type": mesh_type,
        "solver": solver,
        "percent": float(percent),
        "generation_ms": float(mesh.generation_ms),
        "simulation_ms": float(result.simulation_ms),
        "simulation_cpu_ms": float(result.simulation_cpu_ms),
        "iterations": int(result.iterations),
        "force_evaluations": int(result.force_evaluations),
        "hessian_assemblies": int(result.hessian_assemblies),
        "linear_solves": int(result.linear_solves),
        "converged": bool(result.converged),
        # converged with the residual above the tolerance: no representable position is measurably closer
        "converged_to_round_off": bool(result.converged and result.message.startswith("converged to round-off")),
        "residual": float(result.residual),
        "energy": float(result.energy),
        "message": result.message,
        "warnings": [*warnings, *_flat_crease_warning(mesh)],
        "exact_iterations": int(result.exact_iterations),
        "saddle_escapes": int(result.saddle_escapes),
        "continuation_steps": int(result.continuation_steps),
        **state_report(result),
    }
    # metrics.summary also reports mesh counts (as floats): keep the report's own integer counts
    report.update({k: v for k, v in measure(mesh, result, percent).items() if k not in report})
    report["self_intersecting_faces"] = self_intersecting_faces(mesh, result.positions, crossing)
    if constraints is not None and not constraints.empty:
        report.update(constraints.report(mesh, result.positions, start))
    report.update(verdict(mesh, result.fold_angles, percent))  # paper Fig. 7: creases that stay flat or fold wrong
    return report


def refold_mesh(
    mesh: FoldMesh,
    percent: float = 1.0,
    *,
    solver: str = "fast",
    settings: SolverSettings | None = None,
    start: np.ndarray | None = None,
    constraints: Constraints | None = None,
) -> FoldRun:
    """Fold an already built mesh at ``percent``: warm-started from ``start`` (positions in mm) if given, otherwise
    by continuation from the flat sheet (as :func:`fold_pattern`); with ``constraints`` (pins and glue on its
    vertices) if given."""
    result = Solver(mesh, settings, solver, constraints).solve(percent, start=start)
    report = make_report(
        mesh,
        result,
        percent,
        mesh_type=mesh.mesh_type,
        solver=solver,
        warnings=list(mesh.warnings),
        constraints=constraints,
        start=start,
    )
    return FoldRun(mesh, result, report)


def fold_pattern(
    pattern: CreasePattern,
    *,
    angle: float | None = None,
    percent: float = 1.0,
    mesh_type: str = "ruling",
    solver: str = "fast",
    settings: SolverSettings | None = None,
    backend: str = "auto",
    constraints: ConstraintSpec | None = None,
) -> FoldRun:
    """Triangulate ``pattern`` and fold it to equilibrium at ``percent`` (1.0 = 100 %).

    The fast solvers fold along the path paper takes: continuation in the fold percent from the flat sheet
    (``Solver.fold_steps``), so the state reached is the last frame of a 0 → ``percent`` animation, deterministic.

    ``angle`` (degrees) is the target of every M/V crease without one (valley +, mountain −). ``constraints`` (pins
    and glue named by flat points of the pattern) are mapped onto the mesh's vertices.
    """
    from .mesh.build import build_mesh

    pattern = _with_angle(pattern, angle)
    mesh = build_mesh(pattern, mesh_type=mesh_type, backend=backend)
    held = None if constraints is None or constraints.empty else constraints.resolve(mesh)
    result = Solver(mesh, settings, solver, held).solve(percent)
    warnings = list(mesh.warnings)  # build_mesh starts them with the pattern's: adding those again printed them twice
    report = make_report(mesh, result, percent, mesh_type=mesh_type, solver=solver, warnings=warnings, constraints=held)
    return FoldRun(mesh, result, report)
