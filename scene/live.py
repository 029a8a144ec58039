"""Live re-fold: while a folded mesh's Live toggle is on, editing one of its crease curves (or its settings)
re-folds it — the paper's future work, "interactive editing of the crease pattern".

How it stays responsive:

* a persistent ``depsgraph_update_post`` handler only *detects*: it maps updated curve objects/data to the live
  fold objects that use them (:func:`fold_objects_to_refold`) and calls :func:`schedule_refold`;
* :func:`schedule_refold` debounces: it records the object and (re)arms one ``bpy.app.timers`` callback
  :data:`DEBOUNCE_S` after the last edit, so dragging a handle does not queue a fold per mouse move;
* :func:`run_pending` (the timer body, a plain function tests call directly: timers never fire headless) starts one
  live re-fold job per pending object (``folding.refold_job``: warm-started from the current shape, settings-only
  changes re-solve the stored mesh without re-meshing, the iteration cap lowered to :data:`LIVE_MAX_ITERATIONS`);
  :func:`drive_slices` runs them in slices on a timer so the sheet moves while it solves; a new edit supersedes a
  live job still running. Errors go into the object's message;
* a live re-fold never deletes a bake: it is kept, muted and marked out of date (the sidebar offers Re-bake).

The handler ignores the fold objects' own updates (their meshes and crease-display curves), so a re-fold does not
trigger another.
"""

from __future__ import annotations

import time

import bpy
from bpy.app.handlers import persistent

from . import app_handlers, folding, jobs

DEBOUNCE_S = 0.25
"""Quiet time after the last edit before a live re-fold runs."""

LIVE_MAX_ITERATIONS = 40
"""Iteration cap of the fast solver during live re-folds (bounded work per edit)."""

_pending: dict[str, tuple[float, bool]] = {}
"""Fold objects waiting for a live re-fold: name → (time of the last request, whether the mesh must be rebuilt)."""
_guard = {"running": False}


def live_fold_objects(scene: bpy.types.Scene | None = None) -> list[bpy.types.Object]:
    """Fold objects (in ``scene``, or everywhere) whose Live toggle is on."""
    obs = scene.objects if scene is not None else bpy.data.objects
    return [
        ob
        for ob in obs
        if getattr(ob, "curved_fold_mesh", None) is not None
        and ob.curved_fold_mesh.is_fold_mesh
        and ob.curved_fold_mesh.live
    ]


def fold_objects_to_refold(updated_ids, scene: bpy.types.Scene | None = None) -> list[str]:
    """Names of live fold objects that use any of ``updated_ids`` (curve objects or their curve data) as source."""
    names = set()
    for id_ in updated_ids:
        if isinstance(id_, bpy.types.Object) and id_.type == "CURVE":
            names.add(("OB", id_.name))
            names.add(("CU", id_.data.name))
        elif isinstance(id_, bpy.types.Curve):
            names.add(("CU", id_.name))
    if not names:
        return []
    out = []
    for ob in live_fold_objects(scene):
        for src in folding.source_objects(ob):
            if ("OB", src.name) in names or ("CU", src.data.name) in names:
                out.append(ob.name)
                break
    return out


def schedule_refold(name: str, *, rebuild: bool = True) -> None:
    """Ask for a re-fold of the fold object ``name`` after :data:`DEBOUNCE_S` of quiet (debounced).

    ``rebuild=False`` (fold percent, solver changes) only re-solves the stored mesh, warm-started from the current
    shape; a pending rebuild is never downgraded."""
    if _guard["running"]:
        return
    _pending[name] = (time.monotonic(), rebuild or _pending.get(name, (0.0, False))[1])
    if not bpy.app.timers.is_registered(_timer):
        bpy.app.timers.register(_timer, first_interval=DEBOUNCE_S)


def _timer() -> float | None:
    now = time.monotonic()
    waiting = [t for t, _ in _pending.values() if now - t < DEBOUNCE_S]
    if waiting:
        return DEBOUNCE_S - (now - max(waiting))
    run_pending(blocking=False)
    return None


def run_pending(*, blocking: bool = True) -> dict[str, str]:
    """Start a live re-fold job for every pending object (superseding a live job still running on it); returns
    ``{name: "ok" | "running" | error message}``.

    ``blocking`` runs each job to its end here (tests, background mode); otherwise the jobs run in slices on a
    timer (:func:`_drive`), so Blender stays responsive and the sheet moves as it solves. Errors are stored in the
    object's ``last_message`` (shown in the sidebar) instead of raised: a half-edited curve must not break the
    session."""
    results: dict[str, str] = {}
    pending = dict(_pending)
    _pending.clear()
    for name, (_, rebuild) in pending.items():
        ob = bpy.data.objects.get(name)
        if ob is None or not ob.curved_fold_mesh.is_fold_mesh:
            continue
        _guard["running"] = True
        try:
            jobs.stop_live(ob)  # a frame job's partial shape is no start for the re-fold, nor its Esc's restore
            job = jobs.start(
                folding.refold_job(
                    ob,
                    rebuild=None if rebuild else False,
                    max_iterations=LIVE_MAX_ITERATIONS,
                    warm_start=True,
                    live=True,
                )
            )
            if blocking:
                jobs.run_to_end(job)
                results[name] = "ok"
            else:
                _live_jobs[name] = job
                results[name] = "running"
        except jobs.JobBusyError:  # a Re-fold or Bake runs on it: try again after it
            _pending[name] = (time.monotonic(), rebuild)
            results[name] = "busy"
        except folding.engine_errors() as exc:
            ob.curved_fold_mesh.last_message = f"live re-fold failed: {exc}"
            results[name] = str(exc)
        finally:
            _guard["running"] = False
    if _live_jobs and not bpy.app.timers.is_registered(_drive):
        bpy.app.timers.register(_drive, first_interval=0.0)
    if _pending and not bpy.app.timers.is_registered(_timer):
        bpy.app.timers.register(_timer, first_interval=DEBOUNCE_S)
    return results


_live_jobs: dict[str, jobs.Job] = {}
"""Live re-fold jobs running on the timer: fold object name → job."""


def drive_slices(budget_ms: float | None = None) -> bool:
    """One slice of every running live job (the timer body; tests call it directly). Returns True while any job
    still runs."""
    for name, job in list(_live_jobs.items()):
        _guard["running"] = True
        try:
            budget = jobs.SLICE_MS if budget_ms is None else budget_ms
            if jobs.run_slice(job, budget / max(len(_live_jobs), 1)):
                _live_jobs.pop(name, None)
        except Exception as exc:  # noqa: BLE001 - the job has ended (run_slice restored its preview); a traceback out
            # of the timer would stop it for every live fold: one line on the object, as the modal operators report
            _live_jobs.pop(name, None)
            ob = bpy.data.objects.get(name)
            if ob is not None:
                ob.curved_fold_mesh.last_message = f"live re-fold failed: {folding.failure_reason(exc)}"
        finally:
            _guard["running"] = False
        if not job.running:
            _live_jobs.pop(name, None)
    return bool(_live_jobs)


def _drive() -> float | None:
    return 0.01 if drive_slices() else None


@persistent
def on_depsgraph_update(scene, depsgraph) -> None:
    """Detect edits to source curves of live fold objects and schedule debounced re-folds (no work here)."""
    if _guard["running"]:
        return
    updated = [u.id.original if hasattr(u.id, "original") else u.id for u in depsgraph.updates]
    for name in fold_objects_to_refold(updated, scene):
        schedule_refold(name)


def register_extra() -> None:
    app_handlers.attach(bpy.app.handlers.depsgraph_update_post, on_depsgraph_update)


def unregister_extra() -> None:
    app_handlers.detach(bpy.app.handlers.depsgraph_update_post, on_depsgraph_update)
    for timer in (_timer, _drive):
        if bpy.app.timers.is_registered(timer):
            bpy.app.timers.unregister(timer)
    for job in _live_jobs.values():
        jobs.cancel(job)
    _live_jobs.clear()
    _pending.clear()
