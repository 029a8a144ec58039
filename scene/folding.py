"""Folding in the scene: gather source curves, run the engine, write the results onto a fold object.

The scene-level functions an operator calls (one call each: :func:`refold`, :func:`fold_from_pattern`, ...).
Plain functions (no operator state) so the Live handler, the modal and synchronous bake and the tests call the same
code. Everything is computed first (pure ``core``) and written last, so a failure leaves the scene as it was.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import bpy
import numpy as np

from ..core.mesh.fold_mesh import FoldMesh
from ..core.pattern.model import PatternError
from . import bake, mesh_object, pins, self_intersection
from .fold_settings import override_angle_degrees, override_fold_angles, pattern_parameters, settings_dict


@dataclass
class FoldOutcome:
    """What one run produced, before anything is written to the scene."""

    mesh: FoldMesh
    positions: np.ndarray
    fold_angles: np.ndarray | None
    strain_pct: np.ndarray | None
    warp_deg: np.ndarray | None
    report: dict = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)


def engine_errors() -> tuple[type[BaseException], ...]:
    """Exception types the engine raises for bad input or a failed solve (turned into operator reports).

    ``RuntimeError`` (e.g. the ruling swaps' BMesh consistency checks) and ``ArithmeticError`` (overflow) are
    included so an internal engine failure is reported as "Fold failed: ..." with the scene untouched, instead of
    escaping the operator as a traceback."""
    errors: list[type[BaseException]] = [
        PatternError,
        ValueError,
        ArithmeticError,
        RuntimeError,
        np.linalg.LinAlgError,
    ]
    try:
        from ..core.solve.solver import SolverError

        errors.append(SolverError)
    except ImportError:  # pragma: no cover
        pass
    return tuple(errors)


def curve_objects(objects) -> list[bpy.types.Object]:
    """The curve objects among ``objects`` that carry a crease role (others, e.g. crease-display curves, are not)."""
    out = []
    for ob in objects:
        if ob is None or ob.type != "CURVE" or "cf_crease_role" in ob:
            continue
        props = getattr(ob, "curved_fold", None)
        if props is not None and getattr(props, "role", "NONE") == "NONE":
            continue
        out.append(ob)
    return out


def solver_settings(props, *, max_iterations: int | None = None):
    """``core.solver.SolverSettings`` from a fold object's settings (defaults when ``props`` is None);
    ``max_iterations`` caps the solver (live re-folds)."""
    from ..core.solve.solver import SolverSettings

    settings = SolverSettings(**settings_dict(props)) if props is not None else SolverSettings()
    if max_iterations is not None:
        settings.max_iterations = min(settings.max_iterations, int(max_iterations))
    return settings


def pattern_from_objects(objects, *, interval: float = 0.0, tolerance: float = 0.0):
    """Discretised :class:`CreasePattern` of crease curve objects; 0 means automatic for interval/tolerance."""
    from ..core.pattern.discretize import discretize
    from .curves import curves_from_objects, stored_pattern

    if not objects:
        raise PatternError("no crease curves selected: select curve objects that have a crease role")
    stored = stored_pattern(objects)  # an unedited FOLD import: its own pattern, as the command line folds it
    if stored is not None:
        return stored
    curves = curves_from_objects(objects)
    return discretize(curves, interval=interval or None, tolerance=tolerance or None)


def display_metrics(mesh: FoldMesh, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-node strain (%) and per-triangle warp angle (degrees) for the viewport colours (``core.metrics``)."""
    from ..core.metrics import measures as metrics

    return 100.0 * metrics.strain(mesh, positions), metrics.warp_per_triangle(mesh, positions)


def fold_angle_error_message(report: dict) -> str:
    """The paper's Fig. 7 message when the engine judged the pattern as not folding as assigned, else ``""``."""
    if report.get("does_not_fold_as_assigned"):
        return str(report.get("does_not_fold_message") or "does not fold as assigned (large fold-angle error)")
    return ""


def outcome_from_run(run, percent: float) -> FoldOutcome:
    """Turn a ``core.pipeline.FoldRun`` into a :class:`FoldOutcome` with per-node strain and per-face warp."""
    mesh, result = run.mesh, run.result
    pos = np.asarray(result.positions, dtype=np.float64)
    if not np.all(np.isfinite(pos)):
        raise FloatingPointError("the solver returned non-finite positions (the fold diverged)")
    report = dict(run.report)
    strain_pct, warp_deg = display_metrics(mesh, pos)
    return FoldOutcome(
        mesh=mesh,
        positions=pos,
        fold_angles=result.fold_angles,
        strain_pct=strain_pct,
        warp_deg=warp_deg,
        report=report,
        warnings=[str(w) for w in report.get("warnings", mesh.warnings)],
    )


def fold_from_pattern(
    pattern,
    props,
    *,
    percent: float | None = None,
    angle: float | None = None,
    mesh_type: str | None = None,
    solver: str | None = None,
    max_iterations: int | None = None,
) -> FoldOutcome:
    """Mesh and fold ``pattern`` with the settings in ``props`` (a fold object's settings, or None for defaults);
    explicit keyword values win over ``props``. ``percent`` is a fraction (1.0 = 100 %)."""
    from ..core.pipeline import fold_pattern

    pct = (props.fold_percent / 100.0 if props is not None else 1.0) if percent is None else percent
    mesh_type = mesh_type or (props.mesh_type if props is not None else "ruling")
    method = solver or (props.solver if props is not None else "fast")
    if angle is None:
        angle = override_angle_degrees(props)
    pattern = override_fold_angles(
        pattern, angle
    )  # Override Crease Angles applies to every crease, not only unset ones
    run = fold_pattern(
        pattern,
        angle=angle,
        percent=pct,
        mesh_type=mesh_type,
        solver=method,
        settings=solver_settings(props, max_iterations=max_iterations),
    )
    return outcome_from_run(run, pct)


def resolve_stored(
    ob: bpy.types.Object,
    *,
    percent: float | None = None,
    start: np.ndarray | None = None,
    max_iterations: int | None = None,
):
    """Re-solve the FoldMesh stored on ``ob`` (no rebuild) with its current settings."""
    from ..core.pipeline import refold_mesh

    props = ob.curved_fold_mesh
    mesh = mesh_object.read_fold_mesh(ob)
    pct = props.fold_percent / 100.0 if percent is None else percent
    settings = solver_settings(props, max_iterations=max_iterations)
    held = pins.constraints_from_object(ob, mesh)  # pins hold vertices where they are: start from the shape shown
    start = pins.current_positions(ob) if held is not None and start is None else start
    run = refold_mesh(mesh, pct, solver=props.solver, settings=settings, start=start, constraints=held)
    return outcome_from_run(run, pct)


def source_objects(ob: bpy.types.Object) -> list[bpy.types.Object]:
    """The crease curves a fold object was built from: its source collection's curves, or its source list."""
    props = ob.curved_fold_mesh
    if props.source_collection is not None:
        return curve_objects(props.source_collection.all_objects)
    return curve_objects([s.object for s in props.sources if s.object is not None])


def store_outcome(ob: bpy.types.Object, out: FoldOutcome, *, scene=None) -> None:
    """Write positions, attributes, colours and the last-run figures of ``out`` onto the fold object ``ob``."""
    mesh_object.write_results(
        ob,
        out.mesh,
        out.positions,
        fold_angles_sim=out.fold_angles,
        strain_pct=out.strain_pct,
        warp_deg=out.warp_deg,
        scene=scene,
    )
    store_figures(ob, out)


def store_figures(ob: bpy.types.Object, out: FoldOutcome) -> None:
    props = ob.curved_fold_mesh
    rep = out.report
    props.last_vertices = out.mesh.n_vertices
    props.last_faces = out.mesh.n_faces
    props.last_generation_ms = float(rep.get("generation_ms", out.mesh.generation_ms) or 0.0)
    props.last_ms = float(rep.get("simulation_ms", 0.0) or 0.0)
    props.last_iterations = int(rep.get("iterations", 0) or 0)
    props.last_converged = bool(rep.get("converged", False))
    props.last_strain_mean = float(rep["strain_mean_pct"])
    props.last_strain_max = float(rep["strain_max_pct"])
    warp = rep["warp_mean_deg"]
    props.last_warp_mean = float(warp) if np.isfinite(warp) else 0.0
    err = rep.get("fold_angle_error_mean_deg")
    props.last_fold_error = float(err) if err is not None and np.isfinite(err) else 0.0
    props.last_message = fold_angle_error_message(rep)
    self_intersection.write_crossing_colours(ob, out.mesh, out.positions)
    pins.store_figures(ob, rep)


def figures_text(props) -> str:
    """One line with the last run's figures, for reports."""
    return (
        f"{props.last_faces} faces, {props.last_ms:.0f} ms, {props.last_iterations} iterations, "
        f"strain {props.last_strain_mean:.3f} % mean / {props.last_strain_max:.3f} % max, "
        f"warp {props.last_warp_mean:.3f}°" + ("" if props.last_converged else " (not converged)")
    )


def refold(
    ob: bpy.types.Object,
    *,
    rebuild: bool | None = None,
    scene=None,
    max_iterations: int | None = None,
    warm_start: bool = False,
) -> FoldOutcome:
    """Re-fold the fold object ``ob``: rebuild the mesh from its source curves (when it has sources and ``rebuild``
    is not False) or re-solve its stored mesh, then write the result. Any bake is cleared (it would be stale).

    ``warm_start`` starts a re-solve from the current shape instead of the flat sheet (live edits of the fold
    percent). Everything is computed before anything is written; raises the engine's errors unchanged.
    """
    props = ob.curved_fold_mesh
    sources = source_objects(ob)
    if rebuild is None:
        rebuild = bool(sources)
    if rebuild:
        if not sources:
            raise PatternError(f"'{ob.name}' has no source crease curves left to rebuild from")
        pattern = pattern_from_objects(sources, **pattern_parameters(props, scene))
        out = fold_from_pattern(pattern, props, max_iterations=max_iterations)
    else:
        start = None
        if warm_start:
            co = np.empty(3 * len(ob.data.vertices), dtype=np.float32)
            ob.data.attributes["position"].data.foreach_get("vector", co)
            start = co.reshape(-1, 3).astype(np.float64) * mesh_object.mm_per_unit(scene)
        out = resolve_stored(ob, max_iterations=max_iterations, start=start)
    bake.clear_bake(ob)
    props.baked_frames = 0
    results = {"fold_angles_sim": out.fold_angles, "strain_pct": out.strain_pct, "warp_deg": out.warp_deg}
    if rebuild:
        mesh_object.replace_fold_mesh(ob, out.mesh, out.positions, scene=scene, **results)
    else:
        mesh_object.write_results(ob, out.mesh, out.positions, scene=scene, **results)
    store_figures(ob, out)
    return out
