"""The timeline drives the fold: with Fold Percent (or other fold settings) keyframed, a frame change folds the mesh
to that frame's percent — the design's "solver stepped per frame".

* :class:`FrameCache` (one per fold object) keeps every solved frame (fold percent, settings, positions, θ
  history). A new frame a small step after a solved one warm-starts from it (extrapolated in the fold percent), so
  playback costs a few Newton iterations per frame (at most :data:`FRAME_MAX_ITERATIONS`). In a bake any other
  frame is solved from the natural path (``core.solve.path``, whose grid states the frame cache's solver keeps) with
  the whole iteration budget, and is then the static fold at its percent; so is a warm frame that does not converge
  in ``core.solve.path.WARM_MAX_ITERATIONS`` (as in ``core.solve.animation``). Playback warm-starts such frames
  from the nearest solved frame instead (synchronous and capped, it cannot afford a path step), the first frame
  from the path.
  The cache is dropped when the stored mesh changes (re-fold, live edit) and its entries are not reused when the
  solver settings differ. Bakes read it and fill it (``bake.bake_job``): a converged frame is solved once.
* :func:`on_frame_change` (``frame_change_post``) folds each animated fold object that is not showing a current
  bake and has no job running. During playback, a render, in background mode and for a ``frame_set`` called from
  Python (a script, an exporter) it is synchronous, as the caller needs the frame's shape before it draws, renders
  or reads it (capped at :data:`FRAME_MAX_ITERATIONS`). A frame the user steps or scrubs to is a job instead
  (:func:`frame_job`): one slice of ``jobs.SLICE_MS`` in the handler, the rest on a timer (:func:`drive_frames`)
  while the sheet folds in the viewport, solved as a bake solves it (converged, the bake's frame); a newer frame
  change, a Re-fold or a Bake supersedes it (their Esc goes back to the shape from before it), its Cancel button
  leaves the shape as it was, a save or an export finishes it first, and Edit Mode stops it on the shape shown. A
  frame change that another job made pass an object by (a live re-fold, an export) folds it when that job ends
  (:func:`catch_up`). Before
  this, every frame change of a 3,000-face pleat held Blender for 200–460 ms and showed a frame cut short at 12
  iterations.

Quasi-static (equilibrium per frame, the fast solver) is what playback solves; the dynamic bake mode depends on
the history of every earlier frame and is only baked.
"""

from __future__ import annotations

import hashlib
import math
import sys
from collections.abc import Generator
from dataclasses import dataclass

import bpy
import numpy as np
from bpy.app.handlers import persistent

from ..core import as_units
from ..core.pattern.model import PatternError
from ..core.solve.path import WARM_MAX_ITERATIONS
from . import app_handlers, bake, folding, jobs, mesh_object, pins
from .fold_settings import engine_id, settings_dict

FRAME_MAX_ITERATIONS = 12
"""Newton iterations per frame of playback, which is synchronous (Blender needs the frame's shape before it draws
it). Most warm-started frames converge in 2–12; one that does not is shown as it is and reported not converged,
the next one continuing from it. A bake gives warm frames ``core.solve.path.WARM_MAX_ITERATIONS`` instead and
solves a frame that still has not converged from the natural path: with the cap of 12, a 101-frame bake of
CircularPleat-antiFacet, Treble_Clef and Rotating_Star left 22, 16 and 13 frames unconverged (Gauss–Newton's
linear tail, residuals 1e-6 to 5e-3)."""


@dataclass
class CachedFrame:
    """One solved frame: the fold percent (fraction), the settings it was solved with, positions (mm), θ per hinge,
    iterations, convergence and residual."""

    percent: float
    settings: str
    positions: np.ndarray
    theta: np.ndarray
    iterations: int
    converged: bool
    residual: float
    full: bool = False
    """Solved with the whole budget (a bake's or a frame job's), not playback's :data:`FRAME_MAX_ITERATIONS`: if
    it did not converge, solving it again would not either."""


def frozen_settings(props):
    """The solver settings of ``props`` as plain values (what a running job uses: later edits of the object's
    settings, or the object's removal, do not reach into it)."""
    from types import SimpleNamespace

    return SimpleNamespace(**settings_dict(props), solver=str(props.solver))


def settings_key(props) -> str:
    """The solver settings a frame depends on (stiffnesses, isometric, method) as a comparable string."""
    return repr(sorted(settings_dict(props).items())) + props.solver


def mesh_key(ob: bpy.types.Object) -> str:
    """A digest of the stored pattern mesh (flat vertices, triangles, crease targets): the cache's validity."""
    me = ob.data
    h = hashlib.sha1()
    for name, width, key in (("cf_flat", 2, "vector"), ("cf_fold_angle", 1, "value")):
        attr = me.attributes.get(name)
        if attr is None:
            continue
        n = len(attr.data) * width
        buf = np.empty(n, dtype=np.float32)
        attr.data.foreach_get(key, buf)
        h.update(buf.tobytes())
    tri = np.empty(len(me.loops), dtype=np.int32)
    me.loops.foreach_get("vertex_index", tri)
    h.update(tri.tobytes())
    h.update(repr(mesh_object.flat_rescale(me)).encode())  # frames are in mm: a new Unit Scale solves them anew
    return h.hexdigest()


class FrameCache:
    """Solved frames of one fold object's stored mesh (see the module docstring)."""

    def __init__(self, key: str, mesh):
        self.key = key
        self.mesh = mesh
        self.frames: dict[int, CachedFrame] = {}
        self._solvers: dict[str, object] = {}
        self.held = None  # the object's pins and glue (core.solve.constraints.Constraints), set by cache_for
        self._held_key = ""

    def hold(self, held) -> None:
        """Solve the frames with ``held`` (pins and glue, or None): frames solved without them, or with others, no
        longer count as solved."""
        self.held = held
        if held is None:
            self._held_key = ""
        else:
            digest = hashlib.sha1()
            for part in (held.pins, held.pin_targets, held.glue):
                digest.update(np.ascontiguousarray(part).tobytes())
            self._held_key = " held " + digest.hexdigest()

    def settings(self, props) -> str:
        """What a frame depends on besides its percent: the solver settings and the pins and glue."""
        return settings_key(props) + self._held_key

    def solver(self, props):
        """The quasi-static solver for ``props``' settings (kept: its Hessian ordering is paid once)."""
        from ..core.solve.solver import Solver

        key = self.settings(props)
        if key not in self._solvers:
            method = "fast" if props.solver == "FAITHFUL" else engine_id(props.solver)
            settings = folding.solver_settings(props)  # frames are capped per solve (solve_steps)
            self._solvers = {key: Solver(self.mesh, settings, method, self.held)}
        return self._solvers[key]

    def get(self, frame: int, percent: float, props) -> CachedFrame | None:
        """The cached frame if it was solved at this percent with these settings."""
        hit = self.frames.get(int(frame))
        if hit is not None and hit.percent == float(percent) and hit.settings == self.settings(props):
            return hit
        return None

    def start(
        self, frame: int, percent: float, props, fallback: bool = False
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """Start of a new frame's solve: the solved frame that may warm-start it (:func:`.path.warm_startable`:
        a small step forward between the same two grid points of the natural path; the nearest such), extrapolated
        linearly in the fold percent from it and the equilibrium before it on the path (an earlier such frame, else
        the path's grid state), when the step is no longer than theirs. ``(None, None)`` when no frame may: the frame
        is then solved from the natural path, as a static fold is (so it is the static fold at its percent) — unless
        ``fallback`` (playback, capped at :data:`FRAME_MAX_ITERATIONS` per frame, synchronous) and a frame is solved:
        then the nearest solved frame is the start, as before the natural path (a path step from the last grid point
        may need more than the cap — CircularPleat from the flat sheet to 10 % needs ~20 — and would show a frame
        short of its shape; a bake folds such frames along the path with the whole budget)."""
        from ..core.solve.path import extrapolate, warm_startable

        solver = self.solver(props)
        step = solver.settings.continuation_step
        key = self.settings(props)
        usable = sorted(
            (e.percent, e)
            for e in self.frames.values()
            if e.settings == key and warm_startable(e.percent, percent, step)
        )
        if not usable:
            same = {f: e for f, e in self.frames.items() if e.settings == key}
            if fallback and same:
                near = same[min(same, key=lambda f: (abs(f - frame), f))]
                return near.positions, near.theta
            return None, None
        q, near = usable[-1]
        if len(usable) > 1:
            other = usable[-2][1]
            before = (other.percent, other.positions, other.theta)
        else:
            before = solver.path_state(percent)
        return extrapolate(percent, (q, near.positions, near.theta), before)

    def solve_steps(
        self,
        frame: int,
        percent: float,
        props,
        *,
        frame_index: int = 0,
        n_frames: int = 0,
        path_budget: int | None = FRAME_MAX_ITERATIONS,
    ) -> Generator[jobs.Progress, None, CachedFrame]:
        """Solve ``frame`` at ``percent`` warm from a solved frame (:meth:`start`), or from the natural path in at
        most ``path_budget``, one Newton iteration per unit; caches and returns the frame. Playback (``path_budget``
        an int) caps both at :data:`FRAME_MAX_ITERATIONS` (a path state it cuts short is not kept). A bake
        (``path_budget`` ``None``) gives path frames the solver's whole budget, as a static fold, and warm frames
        ``WARM_MAX_ITERATIONS``; a warm frame that does not converge in them is solved from the path. A new
        solver's model and Hessian structure are units of their own (~300 ms in one unit at 3,000 faces before: the
        longest slice of a bake)."""
        new_solver = self.settings(props) not in self._solvers
        solver = self.solver(props)
        if new_solver:
            built = jobs.Progress(
                "model", frame=frame_index + 1, n_frames=n_frames, fraction=frame_index / max(n_frames, 1)
            )
            yield built
            if solver.method != "faithful":  # the ordering in units, the structure, then the scatter indices
                yield from as_units(solver.prepare_steps(), built)
                yield built
        playback = path_budget is not None
        start, theta = self.start(frame, percent, props, fallback=playback)
        warm_budget = FRAME_MAX_ITERATIONS if playback else WARM_MAX_ITERATIONS
        steps = solver.frame_steps(percent, start, theta, warm_budget, path_budget, fall_back=not playback)
        while True:
            try:
                p = next(steps)
            except StopIteration as done:
                r = done.value
                break
            if n_frames:
                fraction = (frame_index + min(p.iteration / 10.0, 0.9)) / n_frames
                yield jobs.Progress("frame", p.iteration, p.residual, frame_index + 1, n_frames, fraction, p.positions)
            else:
                yield jobs.Progress("solve", p.iteration, p.residual, positions=p.positions)
        if not np.all(np.isfinite(r.positions)):
            raise FloatingPointError(f"frame {frame}: the solver returned non-finite positions")
        iterations = r.iterations - r.reused_iterations  # this frame's, not those of the kept path states
        entry = CachedFrame(
            float(percent),
            self.settings(props),
            r.positions,
            r.theta,
            iterations,
            r.converged,
            r.residual,
            full=not playback,
        )
        self.frames[int(frame)] = entry
        return entry


_caches: dict[str, FrameCache] = {}
"""Fold object name → its frame cache."""


def cache_for(ob: bpy.types.Object) -> FrameCache:
    """``ob``'s frame cache, new (empty) when its stored mesh changed since the last one was made."""
    key = mesh_key(ob)
    cache = _caches.get(ob.name)
    if cache is None or cache.key != key:
        cache = FrameCache(key, mesh_object.read_fold_mesh(ob))
        _caches[ob.name] = cache
    try:  # the frames fold with the object's pins and glue, as Fold and Re-fold do
        cache.hold(pins.constraints_from_object(ob, cache.mesh))
    except PatternError:  # mismatched glue groups: Re-fold names the problem; frames fold free meanwhile
        cache.hold(None)
    return cache


def clear(name: str | None = None) -> None:
    """Forget the cache of the fold object ``name`` (all caches with None)."""
    if name is None:
        _caches.clear()
    else:
        _caches.pop(name, None)


def animated(ob: bpy.types.Object) -> bool:
    """Whether any fold setting of ``ob`` is keyframed (F-curves on ``curved_fold_mesh.*``)."""
    if ob.animation_data is None or ob.animation_data.action is None:
        return False
    return any(fc.data_path.startswith("curved_fold_mesh.") for fc in bake._fcurves(ob))


def percent_at(ob: bpy.types.Object, frame: float) -> float:
    """Fold percent (fraction) at ``frame``: the keyframed value, else the set one."""
    fc = bake.percent_fcurve(ob)
    value = fc.evaluate(frame) if fc is not None else ob.curved_fold_mesh.fold_percent
    return float(np.clip(value / 100.0, 0.0, 1.0))


def driven(ob: bpy.types.Object) -> bool:
    """Whether a frame change should fold ``ob``: a fold object with keyframed settings, not in Edit Mode, not showing
    a current bake (an out-of-date one is muted), no job running on it, quasi-static."""
    return _follows_timeline(ob) and not _busy(ob)


def _follows_timeline(ob: bpy.types.Object) -> bool:
    """:func:`driven` but for a job running on ``ob``."""
    props = getattr(ob, "curved_fold_mesh", None)
    if props is None or not props.is_fold_mesh or ob.type != "MESH" or not animated(ob):
        return False
    if ob.mode == "EDIT":  # being edited: its vertices are the user's until Edit Mode is left (a traceback per frame)
        return False
    if props.solver_mode == "DYNAMIC":
        return False
    return not (bake.baked_frames(ob) and not bake.is_stale(ob))


def _busy(ob: bpy.types.Object) -> bool:
    """Whether a job other than a frame job (a live re-fold, an export, a Re-fold) runs on ``ob``."""
    job = jobs.job_on(ob)
    return job is not None and not job.kind.startswith(FRAME_JOB)


FRAME_JOB = "folding frame"
"""The kind of a frame job (:func:`frame_job`): how the progress row and a cancel name it."""


def frame_job(ob: bpy.types.Object, frame: int, *, scene=None) -> jobs.Job:
    """A job that folds ``ob`` to ``frame`` as a bake does (``path_budget=None``: converged, warm from a solved
    frame or from the natural path) in units of one Newton iteration, showing the sheet as it folds, and caches the
    frame; its commit writes the positions and the panel's frame note. Live (``jobs.start`` lets any other job,
    or the next frame's, supersede it), so it never blocks the user's next step. It solves with the settings of
    its start (a stiffness edited meanwhile cached the frame under the new settings, and a Bake took it)."""
    cache = cache_for(ob)
    props = frozen_settings(ob.curved_fold_mesh)
    percent = percent_at(ob, frame)
    handle = jobs.ObjectHandle(ob)

    def steps():
        entry = yield from cache.solve_steps(frame, percent, props, path_budget=None)

        def commit() -> CachedFrame:
            target = handle.get()
            if target is not None:
                mesh_object.update_positions(target, entry.positions, scene=scene)
                _say_frame(target.curved_fold_mesh, frame, entry)
            return entry

        return commit

    return jobs.Job(ob.name, f"{FRAME_JOB} {frame}", steps(), jobs.PositionsPreview(ob, scene), live=True)


_frame_jobs: list[jobs.Job] = []
"""Frame jobs running on the timer (:func:`drive_frames`), each found by its object, not by a name."""


def interactive() -> bool:
    """Whether a frame change may leave its solve to a timer: the user changed the frame (Blender called the handler
    from its own code: a key press, a click or drag in the timeline — not a script's, an exporter's or a ``bpy.ops``
    call's ``frame_set``, which reads the mesh right after it), a window shows the scene, no animation plays and no
    render runs (a render job, or a render operator running modal in a window: Render Animation, Viewport Render
    Animation, which steps the frames itself). Those need each frame's shape before they go on."""
    return not _called_from_python() and _ui_idle()


def _called_from_python() -> bool:
    """Whether Python code is below :func:`on_frame_change` on the stack (it was called by a ``frame_set`` or a
    ``bpy.ops`` call in Python, not by Blender for the user's own frame change). True outside the handler."""
    frame = sys._getframe()
    while frame is not None and frame.f_code is not on_frame_change.__code__:
        frame = frame.f_back
    return frame is None or frame.f_back is not None


def _ui_idle() -> bool:
    """A window shows the scene, no animation plays and no render or bake job runs (see :func:`interactive`).
    Blender's own exporters that step the frames in C (Alembic, USD) and motion paths are not told apart from the
    user here: bake before them, as for any export of the animation."""
    if bpy.app.background or any(bpy.app.is_job_running(kind) for kind in ("RENDER", "OBJECT_BAKE")):
        return False
    wm = bpy.context.window_manager
    windows = list(wm.windows) if wm is not None else []
    if not windows:
        return False
    for w in windows:
        if w.screen is not None and w.screen.is_animation_playing:
            return False
        if any(op.bl_idname.startswith("RENDER_OT_") for op in w.modal_operators):
            return False
    return True


def finish_frame_job(ob: bpy.types.Object | None) -> None:
    """Run the frame job showing its work on ``ob`` (every frame job when ``ob`` is None) to its end, here: an
    export or a save reads the frame the timeline is on (cancelled instead, the previous frame's shape was
    exported, or saved at the new frame)."""
    for job in list(_frame_jobs):
        target = job.preview.edited() if job.preview is not None else None
        if ob is None or (target is not None and target.session_uid == ob.session_uid):
            _frame_jobs.remove(job)
            _run_frame_job(job, math.inf)


def _run_frame_job(job: jobs.Job, budget_ms: float) -> bool:
    """One slice of a frame job, or all of it with an infinite budget (True when it ended). Cancelled when its
    object is gone or no longer driven (Dynamic mode, keys deleted, a current bake); dropped with the shape it
    shows when the user took the object into Edit Mode (restoring would throw them out of it). An error ends the
    job with one line in the object's message, as a playback frame's does."""
    ob = job.preview.edited() if job.preview is not None else None
    if ob is not None and ob.mode == "EDIT":
        jobs.drop(job)
        return True
    if ob is None or not driven(ob):
        jobs.cancel(job)
        return True
    try:
        if math.isinf(budget_ms):
            jobs.run_to_end(job)
            return True
        return jobs.run_slice(job, budget_ms)
    except Exception as exc:  # noqa: BLE001 - the job has ended (run_slice restored its preview): one line
        ob.curved_fold_mesh.last_message = f"{job.kind}: {folding.failure_reason(exc)}"
        return True


def drive_frames(budget_ms: float | None = None) -> bool:
    """One slice of every running frame job, the budget shared (the timer body; tests call it directly). Returns
    True while any job still runs."""
    budget = jobs.SLICE_MS if budget_ms is None else budget_ms
    share = budget / max(len(_frame_jobs), 1)
    for job in list(_frame_jobs):
        if not job.running or _run_frame_job(job, share):
            if job in _frame_jobs:
                _frame_jobs.remove(job)
    return bool(_frame_jobs)


def _drive() -> float | None:
    return 0.01 if drive_frames() else None


def fold_to_frame(ob: bpy.types.Object, frame: int, *, scene=None) -> CachedFrame:
    """Fold ``ob`` to ``frame``'s percent (from the cache, or solved warm from a cached frame or from the natural
    path, :meth:`FrameCache.start`), write the positions and return the frame."""
    cache = cache_for(ob)
    props = ob.curved_fold_mesh
    percent = percent_at(ob, frame)
    entry = cache.get(frame, percent, props)
    if entry is None:
        steps = cache.solve_steps(frame, percent, props)
        while True:
            try:
                next(steps)
            except StopIteration as done:
                entry = done.value
                break
    mesh_object.update_positions(ob, entry.positions, scene=scene)
    return entry


@persistent
def on_frame_change(scene, depsgraph=None) -> None:
    """``frame_change_post``: fold every driven fold object of ``scene`` to the new frame. Errors go to the
    object's message (a bad frame must not break playback). An object another job runs on (a live re-fold, an
    export) is passed by and folded to the frame the timeline is on when that job ends (:func:`catch_up`)."""
    sliced = interactive()
    started = False
    for ob in list(scene.objects):
        if not _follows_timeline(ob):
            continue
        if _busy(ob):
            _missed[ob.session_uid] = (jobs.ObjectHandle(ob), scene.session_uid)
            continue
        started |= _show_frame(ob, scene, sliced)
    # the new jobs' first slice here, one budget shared (a frame a few iterations from a solved one ends in it);
    # the rest on the timer
    if started:
        _drive_on()
    if _missed and not bpy.app.background and not bpy.app.timers.is_registered(_catch_up):
        bpy.app.timers.register(_catch_up, first_interval=CATCH_UP_S)


def _show_frame(ob: bpy.types.Object, scene, sliced: bool) -> bool:
    """Fold ``ob`` (driven) to ``scene``'s current frame: from the cache, synchronously, or (``sliced``) by a frame
    job whose first slice is left to the caller (:func:`_drive_on`). True when a frame job was started."""
    frame = scene.frame_current
    try:
        jobs.stop_live(ob)  # an earlier frame's job: this frame supersedes it
        if sliced:
            entry = cache_for(ob).get(frame, percent_at(ob, frame), ob.curved_fold_mesh)
            if entry is None or not (entry.converged or entry.full):
                _frame_jobs.append(jobs.start(frame_job(ob, frame, scene=scene)))
                return True
            mesh_object.update_positions(ob, entry.positions, scene=scene)
        else:
            entry = fold_to_frame(ob, frame, scene=scene)
    except folding.engine_errors() as exc:
        ob.curved_fold_mesh.last_message = f"frame {frame}: {exc}"
        return False
    _say_frame(ob.curved_fold_mesh, frame, entry)
    return False


def _drive_on() -> None:
    """One slice of the frame jobs now, the rest on the timer (:func:`_drive`)."""
    if drive_frames() and not bpy.app.timers.is_registered(_drive):
        bpy.app.timers.register(_drive, first_interval=0.0)


_missed: dict[int, tuple[jobs.ObjectHandle, int]] = {}
"""Objects a frame change passed by because another job ran on them: ``session_uid`` → (the object, its scene's
``session_uid``). A frame stepped to during a live re-fold or an export was ignored, and after the job the object
showed the old frame's shape at the new frame until the next frame change (a reviewer session)."""

CATCH_UP_S = 0.1
"""How often (s) the timer of :func:`catch_up` looks whether the jobs that made frame changes pass by have ended."""


def catch_up() -> bool:
    """Fold each object a frame change passed by (:data:`_missed`) to the frame its scene is on, once no other job
    runs on it: as a frame change would (a frame job in the interface, synchronously else). Returns True while
    some still wait for their job (the timer's body, :func:`_catch_up`; tests call it directly)."""
    started = False
    for uid, (handle, scene_uid) in list(_missed.items()):
        ob = handle.get()
        if ob is not None and _busy(ob):
            continue
        del _missed[uid]
        scene = _scene_of(ob, scene_uid) if ob is not None else None
        if scene is not None and driven(ob):
            started |= _show_frame(ob, scene, _ui_idle())
    if started:
        _drive_on()
    return bool(_missed)


def _scene_of(ob: bpy.types.Object, scene_uid: int):
    """The scene whose frame ``ob`` follows: the one it was passed by in (found by ``session_uid``: a rename keeps
    it), else the first it is in now (moved meanwhile); None when it is in none."""
    scenes = list(ob.users_scene)
    return next((s for s in scenes if s.session_uid == scene_uid), scenes[0] if scenes else None)


def _catch_up() -> float | None:
    return CATCH_UP_S if catch_up() else None


FRAME_NOTE = "not converged in"
"""What a frame's note says (:func:`_say_frame`), so the next converged frame clears only such a note."""


def _say_frame(props, frame: int, entry: CachedFrame) -> None:
    """Show on the panel whether the frame just shown converged: playback stopped it at
    :data:`FRAME_MAX_ITERATIONS` without a word, and the panel still showed the static fold's figures (a designer
    session counted 16 unconverged frames of 60 on Carved_Cylinder). A converged frame clears such a note."""
    if not entry.converged:
        if entry.full:  # a bake's budget: baking again gives the same
            note = f"frame {frame}: {FRAME_NOTE} the solver's whole budget (residual {entry.residual:.1e})"
        else:
            note = (
                f"frame {frame}: {FRAME_NOTE} playback's {FRAME_MAX_ITERATIONS} iterations "
                f"(residual {entry.residual:.1e}); Bake solves it fully"
            )
        if props.last_message != note:
            props.last_message = note
    elif props.last_message.startswith("frame ") and FRAME_NOTE in props.last_message:
        props.last_message = ""


@persistent
def on_load(*_args) -> None:
    """A file was loaded: jobs and caches belong to the previous one."""
    jobs.cancel_all()
    _frame_jobs.clear()
    _missed.clear()
    _caches.clear()


@persistent
def on_undo(*_args) -> None:
    """Undo or redo is about to restore an earlier state: running jobs stop first (their previews restored), as Esc
    stops them. A Re-fold running through Ctrl+Z ended with "the scene changed while it ran (ReferenceError: StructRNA
    of type Scene has been removed)" (a designer session); the undo then takes the scene back as it does."""
    jobs.cancel_all()
    _frame_jobs.clear()
    _missed.clear()


@persistent
def on_save_pre(*_args) -> None:
    """A save is about to write the file: frame jobs end first (the file holds the frame it is saved on, not the
    previous frame's shape at the new frame), then the other running jobs' previews come off
    (:func:`jobs.hide_previews`)."""
    finish_frame_job(None)
    jobs.hide_previews()


@persistent
def on_save_post(*_args) -> None:
    """The file is written: the running jobs' previews go back on, and the jobs go on."""
    jobs.show_previews()


UNDO_HANDLERS = ("undo_pre", "redo_pre")
SAVE_HANDLERS = (("save_pre", on_save_pre), ("save_post", on_save_post))


def register_extra() -> None:
    app_handlers.attach(bpy.app.handlers.frame_change_post, on_frame_change)
    app_handlers.attach(bpy.app.handlers.load_pre, on_load)
    for name in UNDO_HANDLERS:
        app_handlers.attach(getattr(bpy.app.handlers, name), on_undo)
    for name, function in SAVE_HANDLERS:
        app_handlers.attach(getattr(bpy.app.handlers, name), function)


def unregister_extra() -> None:
    app_handlers.detach(bpy.app.handlers.frame_change_post, on_frame_change)
    app_handlers.detach(bpy.app.handlers.load_pre, on_load)
    for name in UNDO_HANDLERS:
        app_handlers.detach(getattr(bpy.app.handlers, name), on_undo)
    for name, function in SAVE_HANDLERS:
        app_handlers.detach(getattr(bpy.app.handlers, name), function)
    for timer in (_drive, _catch_up):
        if bpy.app.timers.is_registered(timer):
            bpy.app.timers.unregister(timer)
    jobs.cancel_all()
    _frame_jobs.clear()
    _missed.clear()
    _caches.clear()
