"""Folding in the scene: gather source curves, run the engine, write the results onto a fold object.

The scene-level functions an operator calls (one call each: :func:`refold`, :func:`fold_from_pattern`, ...).
Plain functions (no operator state) so the Live handler, the modal and synchronous bake and the tests call the same
code. Everything is computed first (pure ``core``) and written last, so a failure leaves the scene as it was.
"""

from __future__ import annotations

import time
from collections.abc import Generator
from dataclasses import dataclass, field
from typing import Any

import bpy
import numpy as np

from ..core import as_units
from ..core.mesh.fold_mesh import FoldMesh
from ..core.mesh.transfer import carried_shape_steps
from ..core.pattern.model import PatternError
from . import bake, jobs, mesh_object, pins, self_intersection, source_state
from .curves import curve_objects, shown_crease_curves
from .fold_settings import (
    engine_id,
    override_angle_degrees,
    override_fold_angles,
    pattern_parameters,
    settings_dict,
)


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
    crossing: np.ndarray | None = None
    """Per triangle: does it pass through a non-adjacent one (measured once, for the report and the colours)."""


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


def failure_reason(exc: BaseException) -> str:
    """What a job's failure tells the user, in one line: the engine's own message, or, for anything else (the user
    changed the scene under the job), "the scene changed while it ran (…)". The modal operators and the live
    re-folds' timer say it alike."""
    if isinstance(exc, engine_errors()):
        return str(exc)
    return f"the scene changed while it ran ({type(exc).__name__}: {exc})"


def solver_settings(props, *, max_iterations: int | None = None):
    """``core.solve.solver.SolverSettings`` from a fold object's settings (defaults when ``props`` is None);
    ``max_iterations`` caps the solver (live re-folds)."""
    from ..core.solve.solver import SolverSettings

    settings = SolverSettings(**settings_dict(props)) if props is not None else SolverSettings()
    if max_iterations is not None:
        settings.max_iterations = min(settings.max_iterations, int(max_iterations))
    return settings


def pattern_from_objects(objects, *, interval: float = 0.0, tolerance: float = 0.0):
    """Discretised :class:`CreasePattern` of crease curve objects; 0 means automatic for interval/tolerance."""
    from ..core import run_to_end

    return run_to_end(pattern_steps(objects, interval=interval, tolerance=tolerance))


def pattern_steps(
    objects, *, interval: float = 0.0, tolerance: float = 0.0, notes: list[str] | None = None
) -> Generator[str, None, Any]:
    """:func:`pattern_from_objects` in units for a job: reading the curves from the scene (units of
    ``curves.READ_UNIT_MS``), then each step of the discretisation (``core.pattern.discretize.discretize_steps``);
    yields the unit's name, returns the pattern. ``notes``: warnings about the choice of curves (hidden ones left
    out), put first."""
    from ..core.pattern.discretize import discretize_steps
    from .curves import curves_steps, stored_pattern

    if not objects:
        raise PatternError("no crease curves selected: select curve objects that have a crease role")
    # an unedited FOLD import: its own pattern, as the command line folds it
    stored = stored_pattern(objects, interval=interval or None, tolerance=tolerance or None)
    if stored is not None:
        stored.warnings = [*(notes or []), *stored.warnings]
        return stored
    notes = list(notes or [])  # and spline-level warnings (a one-point spline, modifiers not folded, ...)
    curves = yield from as_units(curves_steps(objects, warnings=notes), "reading curves")
    yield "curves read"
    pattern = yield from discretize_steps(curves, interval=interval or None, tolerance=tolerance or None)
    pattern.warnings = notes + list(pattern.warnings)
    return pattern


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
    mesh_type = engine_id(mesh_type or (props.mesh_type if props is not None else "RULING"))
    method = engine_id(solver or (props.solver if props is not None else "FAST"))
    if angle is None:
        angle = override_angle_degrees(props)
    pattern = override_fold_angles(pattern, angle)  # Override Crease Angles applies to every crease
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
    run = refold_mesh(mesh, pct, solver=engine_id(props.solver), settings=settings, start=start, constraints=held)
    return outcome_from_run(run, pct)


def source_objects(ob: bpy.types.Object) -> list[bpy.types.Object]:
    """The crease curves a fold object was built from: its source collection's curves, or its source list."""
    props = ob.curved_fold_mesh
    if props.source_collection is not None:
        return shown_crease_curves(props.source_collection)[0]
    return curve_objects([s.object for s in props.sources if s.object is not None])


def hidden_sources_notes(coll: bpy.types.Collection | None) -> list[str]:
    """The warning naming the crease curves of ``coll`` the viewport hides (left out of its fold), if any."""
    return shown_crease_curves(coll)[1] if coll is not None else []


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
    cpu = rep.get("simulation_cpu_ms")
    props.last_cpu_ms = float(cpu) if cpu is not None and np.isfinite(cpu) else 0.0
    props.last_iterations = int(rep.get("iterations", 0) or 0)
    props.last_converged = bool(rep.get("converged", False))
    props.last_strain_mean = float(rep["strain_mean_pct"])
    props.last_strain_max = float(rep["strain_max_pct"])
    warp = rep["warp_mean_deg"]
    props.last_warp_mean = float(warp) if np.isfinite(warp) else 0.0
    err = rep.get("fold_angle_error_mean_deg")
    props.last_fold_error = float(err) if err is not None and np.isfinite(err) else 0.0
    props.last_message = fold_angle_error_message(rep)
    self_intersection.write_crossing_colours(ob, out.mesh, out.positions, out.crossing)
    pins.store_figures(ob, rep)


def figures_text(props) -> str:
    """One line with the last run's figures, for reports."""
    return (
        f"{props.last_faces} faces, {props.last_ms:.0f} ms ({props.last_cpu_ms:.0f} ms CPU), "
        f"{props.last_iterations} iterations, "
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
    live: bool = False,
) -> FoldOutcome:
    """Re-fold the fold object ``ob`` in one blocking call: :func:`refold_job` run to its end (scripts). Raises the
    engine's errors unchanged, with the scene as it was."""
    job = refold_job(ob, rebuild=rebuild, scene=scene, max_iterations=max_iterations, warm_start=warm_start, live=live)
    return jobs.run_to_end(jobs.start(job))


# ------------------------------------------------------------------------------------------ sliced jobs


def solve_progress(
    solver,
    percent: float,
    *,
    start: np.ndarray | None = None,
    theta_prev: np.ndarray | None = None,
    velocities: np.ndarray | None = None,
    chunk_ms: float = 30.0,
) -> Generator[jobs.Progress, None, Any]:
    """One solve of ``solver`` at ``percent`` in units of work: a Newton iteration (fast methods,
    ``Solver.solve_steps``) or a chunk of explicit steps (faithful; chunks are multiples of ``check_every`` so the
    convergence checks fall on the same steps as in one call: the result equals ``Solver.solve``'s). Yields
    :class:`jobs.Progress` with the positions reached; returns the ``FoldResult``."""
    from dataclasses import replace

    if solver.method != "faithful":
        steps = solver.solve_steps(percent, start=start, theta_prev=theta_prev)
        while True:
            try:
                p = next(steps)
            except StopIteration as done:
                return done.value
            cap = max(int(solver.settings.max_iterations), 1)
            yield jobs.Progress(
                "solve", p.iteration, p.residual, fraction=min(p.iteration / cap, 1.0), positions=p.positions
            )
    s = solver.settings
    check = max(int(s.check_every), 1)
    chunk = check
    total = None
    x, theta, v = start, theta_prev, velocities
    done_steps, evaluations, ms, cpu = 0, 0, 0.0, 0.0
    while True:
        n = min(chunk, s.max_steps - done_steps)
        t0 = time.perf_counter()
        r = solver.solve(percent, start=x, theta_prev=theta, velocities=v, max_steps=n)
        dt_ms = 1e3 * (time.perf_counter() - t0)
        done_steps += r.iterations
        evaluations += r.force_evaluations
        ms += r.simulation_ms
        cpu += r.simulation_cpu_ms
        x, theta, v = r.positions, r.theta, r.velocities
        total = r
        if r.converged or done_steps >= s.max_steps or r.iterations < n:
            break
        if s.time_limit is not None and ms > 1e3 * s.time_limit:
            break
        yield jobs.Progress(
            "solve", done_steps, r.residual, fraction=done_steps / max(s.max_steps, 1), positions=r.positions
        )
        per_step = dt_ms / max(r.iterations, 1)
        chunk = max(check, int(chunk_ms / max(per_step, 1e-6)) // check * check)
    return replace(total, iterations=done_steps, force_evaluations=evaluations, simulation_ms=ms, simulation_cpu_ms=cpu)


def _mesh_steps(pattern_units, angle, mesh_type) -> Generator[jobs.Progress, None, Any]:
    """Discretise (in the units of ``pattern_units``, a :func:`pattern_steps` generator), then triangulate with the
    ruling swaps (in units, ``build_mesh_steps``); returns the FoldMesh and its warnings (the pattern's first). Each
    unit is usually under 100 ms; docs/benchmarks.md lists where it is not."""
    from ..core.mesh.build import build_mesh_steps
    from ..core.pipeline import _with_angle

    pattern = yield from as_units(pattern_units, jobs.Progress("discretise"))
    pattern = _with_angle(override_fold_angles(pattern, angle), angle)  # Override applies to every crease
    yield jobs.Progress("mesh")
    mesh = yield from as_units(build_mesh_steps(pattern, mesh_type=engine_id(mesh_type)), jobs.Progress("mesh"))
    yield jobs.Progress("model")
    return mesh, list(mesh.warnings)  # build_mesh puts the pattern's warnings first


def _solve_steps(mesh, settings, percent, method, *, start=None, warnings=None, constraints=None):
    """Build the model (one unit), then solve in units (with ``constraints``: pins and glue); returns the
    :class:`FoldOutcome`."""
    from ..core.pipeline import FoldRun, make_report
    from ..core.solve.solver import Solver

    method = engine_id(method)
    solver = Solver(mesh, settings, method, constraints)
    if method != "faithful":  # the Hessian's ordering (one component per unit) and structure, in units of their own
        yield from as_units(solver.prepare_steps(), jobs.Progress("model"))
    yield jobs.Progress("solve")
    result = yield from solve_progress(solver, percent, start=start)
    yield jobs.Progress("figures")  # the self-intersection test and the report: a unit each (~35 ms at 3,000 faces)
    crossing = None
    if np.all(np.isfinite(result.positions)):
        from ..core.metrics.intersections import intersecting_faces_steps

        positions = np.asarray(result.positions, dtype=np.float64)
        crossing = yield from as_units(intersecting_faces_steps(positions, mesh.triangles), jobs.Progress("figures"))
        yield jobs.Progress("figures")
    report = make_report(
        mesh,
        result,
        percent,
        mesh_type=mesh.mesh_type,
        solver=method,
        warnings=list(warnings or mesh.warnings),
        constraints=constraints,
        start=start,
        crossing=crossing,
    )
    out = outcome_from_run(FoldRun(mesh, result, report), percent)
    out.crossing = crossing
    return out


@dataclass
class FoldOptions:
    """The Fold operator's options: pattern parameters and fold settings of a new fold object."""

    interval: float = 0.0
    tolerance: float = 0.0
    mesh_type: str = "RULING"
    use_fold_angle: bool = False
    fold_angle: float = 180.0
    fold_percent: float = 100.0
    solver: str = "FAST"


def new_fold_name(sources, coll) -> str:
    """Name of the fold object made from ``sources`` (or the collection ``coll``): ``mesh_object.fold_object_name``."""
    return mesh_object.fold_object_name(coll, sources)


def fold_job(sources, coll, options: FoldOptions, *, scene=None) -> jobs.Job:
    """The Fold operator's one scene call: a job that meshes and folds ``sources`` (crease curves of ``coll`` or
    the selection) and, when done, creates the fold object beside them and returns ``(object, FoldOutcome)``.
    Raises the engine's errors for an empty selection before any work."""
    if not sources:
        raise PatternError("no crease curves selected: select curve objects that have a crease role")
    target = sources[0].users_collection[0] if sources[0].users_collection else bpy.context.scene.collection
    target_name = target.name
    name = jobs.free_owner(new_fold_name(sources, coll))
    source_handles = [jobs.ObjectHandle(s) for s in sources]
    coll_name = coll.name if coll is not None else None
    sources_fingerprint = source_state.fingerprint(sources, scene)  # the curves as this job reads them
    preview = jobs.MeshPreview(
        name, collection=target, scene=scene, place=lambda tmp: mesh_object.place_beside(tmp, sources)
    )

    notes = hidden_sources_notes(coll)

    def steps():
        mesh, warnings = yield from _mesh_steps(
            pattern_steps(sources, **pattern_parameters(options, scene), notes=notes),
            override_angle_degrees(options),
            options.mesh_type,
        )
        preview.set_mesh(mesh)
        pct = options.fold_percent / 100.0
        out = yield from _solve_steps(mesh, solver_settings(None), pct, options.solver, warnings=warnings)

        def commit():
            now = [h.require("crease curve") for h in source_handles]
            try:
                target.name  # noqa: B018 - a removed collection raises ReferenceError here
            except ReferenceError:
                raise RuntimeError(
                    f"the collection '{target_name}' was deleted while the job ran; nothing was written"
                ) from None
            return create_fold(out, now, coll_name, options, target, scene, fingerprint=sources_fingerprint), out

        return commit

    return jobs.Job(name, "folding", steps(), preview)


def create_fold(
    out: FoldOutcome, sources, coll_name, options: FoldOptions, target, scene=None, *, fingerprint: str | None = None
) -> bpy.types.Object:
    """Write a fold outcome as a new fold object (all or nothing) with its recipe and the ``fingerprint`` of the
    curves it was made from (:func:`source_state.record`: inside the all or nothing, where a failure had left the
    half-made object and its crease curves behind); returns the object."""
    coll = bpy.data.collections.get(coll_name) if coll_name else None
    ob = None
    try:
        ob = mesh_object.create_fold_object(
            out.mesh,
            out.positions,
            new_fold_name(sources, coll),
            target,
            fold_angles_sim=out.fold_angles,
            strain_pct=out.strain_pct,
            warp_deg=out.warp_deg,
            scene=scene,
        )
        mesh_object.place_beside(ob, sources)  # beside the curves and earlier folds
        props = ob.curved_fold_mesh
        props.is_fold_mesh = True
        props.source_collection = coll
        for src in sources:
            props.sources.add().object = src
        props.interval, props.tolerance, props.mesh_type = options.interval, options.tolerance, options.mesh_type
        props.use_fold_angle, props.fold_angle = options.use_fold_angle, options.fold_angle
        props.fold_percent, props.solver = options.fold_percent, options.solver
        store_figures(ob, out)
        source_state.record(ob, fingerprint)
    except Exception as exc:  # any write failure: remove what was made, leave the scene as it was
        mesh_object.remove_fold_object(ob)
        raise RuntimeError(f"writing the mesh failed: {exc}") from exc
    return ob


def same_mesh(a: FoldMesh, b: FoldMesh) -> bool:
    """Whether two fold meshes are the same pattern mesh (flat vertices, triangles, crease targets), up to the
    float32 rounding of a mesh stored on an object (1e-7 of the sheet's size, 1e-4° of a target)."""
    if a.vertices.shape != b.vertices.shape or not np.array_equal(a.triangles, b.triangles):
        return False
    if a.edges.shape != b.edges.shape:
        return False
    size = max(float(np.ptp(a.vertices)), 1.0)
    n = len(a.vertices)

    def by_edge(m):  # edges in a canonical order: a stored mesh lists them in Blender's order
        e = np.sort(m.edges, axis=1)
        order = np.argsort(e[:, 0] * n + e[:, 1])
        return e[order], np.nan_to_num(m.fold_angles[order], nan=1e9), np.asarray(m.assignments)[order]

    (ea, fa, aa), (eb, fb, ab) = by_edge(a), by_edge(b)
    return bool(
        np.allclose(a.vertices, b.vertices, rtol=0.0, atol=1e-6 * size)
        and np.array_equal(ea, eb)
        and np.allclose(fa, fb, rtol=0.0, atol=1e-4)
        and np.array_equal(aa, ab)
    )


def refold_job(
    ob: bpy.types.Object,
    *,
    rebuild: bool | None = None,
    scene=None,
    max_iterations: int | None = None,
    warm_start: bool = False,
    live: bool = False,
) -> jobs.Job:
    """The Re-fold (and live re-fold) operator's one scene call: a job that rebuilds the mesh from the source
    curves (``rebuild`` True, or None with sources) or re-solves the stored mesh, warm-started from the current
    shape with ``warm_start``; its commit writes the result and returns the :class:`FoldOutcome`.

    A rebuild that yields the same mesh as the stored one keeps the mesh (no re-meshing). An explicit re-fold
    clears a bake (stale); a ``live`` one keeps it, marked out of date (:func:`bake.mark_stale`)."""
    jobs.stop_live(ob)  # a frame job's partial shape is neither the warm start nor what Esc restores
    props = ob.curved_fold_mesh
    sources = source_objects(ob)
    if rebuild is None:
        rebuild = bool(sources)
    if rebuild and not sources:
        raise PatternError(f"'{ob.name}' has no source crease curves left to rebuild from")
    name = ob.name
    handle = jobs.ObjectHandle(ob)
    sources_fingerprint = source_state.fingerprint(sources, scene) if rebuild else None  # as this job reads them
    stored = mesh_object.read_fold_mesh(ob)
    held = pins.constraints_from_object(ob, stored, scene)  # pins hold vertices where they are: start from the
    start = pins.current_positions(ob, scene) if warm_start or held is not None else None  # shape shown
    pct = props.fold_percent / 100.0
    method = props.solver
    angle = override_angle_degrees(props)
    settings = solver_settings(props, max_iterations=max_iterations)  # the job keeps the settings of its start
    fresh_settings = solver_settings(props)  # a fold from the flat sheet gets the whole budget, live or not
    mesh_type = props.mesh_type
    parameters = pattern_parameters(props, scene)
    hidden_notes = hidden_sources_notes(props.source_collection)
    positions_preview = jobs.PositionsPreview(ob, scene)
    mesh_preview = jobs.MeshPreview(name, ob=ob, scene=scene)
    previews = _Previews(positions_preview)

    def steps():
        mesh, warnings, remesh = stored, list(stored.warnings), False
        if rebuild:
            built, warnings = yield from _mesh_steps(
                pattern_steps(sources, **parameters, notes=hidden_notes),
                angle,
                mesh_type,
            )
            if not same_mesh(built, stored):
                mesh, remesh = built, True
                mesh_preview.set_mesh(mesh)
                previews.active = mesh_preview
        x0 = start  # a rebuild carries the shape over, in units (None: the creases moved, fold afresh)
        if remesh:
            x0 = yield from as_units(carried_shape_steps(stored, start, mesh), jobs.Progress("model"))
        constraints = None if remesh else held  # pins and glue name vertices of the stored mesh
        use = settings if x0 is not None else fresh_settings
        out = yield from _solve_steps(mesh, use, pct, method, start=x0, warnings=warnings, constraints=constraints)
        return lambda: write_refold(
            handle.require("fold object"),
            out,
            remesh=remesh,
            keep_bake=live,
            scene=scene,
            sources_fingerprint=sources_fingerprint,
        )

    return jobs.Job(name, "live re-fold" if live else "re-folding", steps(), previews, live=live)


class _Previews:
    """The preview a re-fold shows: positions on the object, or a new mesh once the pattern was re-meshed."""

    def __init__(self, active):
        self.active = active

    def show(self, positions):
        self.active.show(positions)

    def restore(self):
        self.active.restore()

    def edited(self):
        return self.active.edited()


def write_refold(
    ob: bpy.types.Object,
    out: FoldOutcome,
    *,
    remesh: bool,
    keep_bake: bool,
    scene=None,
    sources_fingerprint: str | None = None,
) -> FoldOutcome:
    """Write a re-fold's outcome onto ``ob`` (a new mesh when ``remesh``) and return it. A bake is kept and marked
    out of date with ``keep_bake`` (live re-folds), else cleared. ``sources_fingerprint`` (a rebuild from the
    curves: :func:`source_state.fingerprint` of them when the job started) is stored as the curves the mesh matches."""
    results = {"fold_angles_sim": out.fold_angles, "strain_pct": out.strain_pct, "warp_deg": out.warp_deg}
    had_bake = bool(bake.baked_frames(ob))
    if had_bake and not keep_bake:
        bake.clear_bake(ob)
        ob.curved_fold_mesh.baked_frames = 0
        bake.forget_stale(ob)
    if remesh:
        base = bake.keep_stale_mesh(ob) if had_bake and keep_bake else None
        try:
            mesh_object.replace_fold_mesh(ob, out.mesh, out.positions, scene=scene, **results)
        except Exception:
            if base is not None:
                bake.restore_stale_mesh(ob, base)
            raise
        if base is not None:
            ob.data.name = base
    else:
        mesh_object.write_results(ob, out.mesh, out.positions, scene=scene, **results)
    if had_bake and keep_bake:
        bake.mark_stale(ob)
    store_figures(ob, out)
    source_state.record(ob, sources_fingerprint)
    return out
