"""Bake operator: fold the active folded mesh frame by frame over the scene's range and store one shape key per
frame (keyed, so playback and glTF export need no add-on), plus Clear Bake.

The fold percent per frame comes from the object's keyframed ``Fold Percent`` when it is animated, else it ramps
linearly from 0 at the first frame to the set percent at the last. Each frame warm-starts from the previous one
(``core.animation.FoldAnimation``: quasi-static or dynamic). The work lives in :class:`BakeJob` so that the
synchronous ``execute()`` (scripts, tests, background mode) and the modal timer (interactive: a time budget per
tick, progress in the status bar, Esc cancels) run the same code. Nothing is written until every frame is
computed, so cancelling or failing leaves the object exactly as before.
"""

from __future__ import annotations

import time

import bpy
import numpy as np

from ..scene import bake, folding, mesh_object
from . import _common

TICK_BUDGET_S = 0.03
"""Computation per modal timer tick (seconds), so the interface stays responsive."""

RUNNING: dict[str, float] = {}
"""Modal bakes in progress: fold object name → fraction done (the sidebar draws it as a progress bar)."""


def percent_schedule(ob: bpy.types.Object, frames: list[int]) -> np.ndarray:
    """Fold percent (fraction) per frame: the keyframed ``curved_fold_mesh.fold_percent`` if animated, else a
    linear ramp from 0 to the set percent over ``frames``."""
    props = ob.curved_fold_mesh
    anim = ob.animation_data
    fc = None
    if anim is not None and anim.action is not None:
        fc = next(
            (f for f in bake._fcurves(ob) if f.data_path == "curved_fold_mesh.fold_percent"),
            None,
        )
    if fc is not None:
        return np.clip(np.array([fc.evaluate(f) for f in frames], dtype=np.float64) / 100.0, 0.0, 1.0)
    if len(frames) == 1:
        return np.array([props.fold_percent / 100.0])
    return np.linspace(0.0, props.fold_percent / 100.0, len(frames))


class _WarmStartStepper:
    """Per-frame solves warm-started from the previous frame, used when ``core.animation`` is not available."""

    def __init__(self, mesh, settings, method: str):
        from ..core.solve.solver import Solver

        self.solver = Solver(mesh, settings, method)
        self.previous = None

    def frame(self, percent: float):
        result = self.solver.solve(percent, start=self.previous)
        self.previous = result.positions
        return result


def make_stepper(mesh, props):
    """``core.animation.FoldAnimation`` for ``mesh`` with the object's mode/steps/stiffness (or a warm-start
    fallback while that module is missing)."""
    settings = folding.solver_settings(props)
    try:
        from ..core.solve.animation import FoldAnimation
    except ImportError:
        return _WarmStartStepper(mesh, settings, props.solver)
    mode = "dynamic" if props.solver_mode == "DYNAMIC" else "quasi_static"
    return FoldAnimation(mesh, settings, mode=mode, steps_per_frame=props.steps_per_frame)


class BakeJob:
    """All frames of one bake, computed step by step (:meth:`step`) and written at once (:meth:`write`)."""

    def __init__(self, ob: bpy.types.Object, frames: list[int]):
        if not frames:
            raise ValueError("the frame range is empty")
        self.ob_name = ob.name
        self.mesh = mesh_object.read_fold_mesh(ob)
        self.frames = list(frames)
        self.percents = percent_schedule(ob, self.frames)
        self.stepper = make_stepper(self.mesh, ob.curved_fold_mesh)
        self.positions: list[np.ndarray] = []
        self.iterations = 0
        self.unconverged: list[int] = []
        self.ms = 0.0

    @property
    def done(self) -> bool:
        return len(self.positions) == len(self.frames)

    @property
    def progress(self) -> float:
        return len(self.positions) / len(self.frames)

    def step(self, budget_s: float | None = None) -> None:
        """Compute frames until done or ``budget_s`` seconds have passed (at least one frame)."""
        t0 = time.perf_counter()
        while not self.done:
            i = len(self.positions)
            result = self.stepper.frame(float(self.percents[i]))
            pos = np.asarray(result.positions, dtype=np.float64)
            if not np.all(np.isfinite(pos)):
                raise FloatingPointError(f"frame {self.frames[i]}: the solver returned non-finite positions")
            self.positions.append(pos)
            self.iterations += int(getattr(result, "iterations", 0) or 0)
            if not getattr(result, "converged", True):
                self.unconverged.append(self.frames[i])
            if budget_s is not None and time.perf_counter() - t0 >= budget_s:
                break
        self.ms += 1e3 * (time.perf_counter() - t0)

    def write(self, scene=None) -> bpy.types.Object:
        """Write every computed frame as keyed shape keys (all or nothing); returns the object."""
        ob = bpy.data.objects[self.ob_name]
        bake.bake_shape_keys(ob, self.frames, self.positions, scene=scene)
        ob.curved_fold_mesh.baked_frames = len(self.frames)
        strain_pct, warp_deg = folding.display_metrics(self.mesh, self.positions[-1])
        me = ob.data
        mesh_object.write_colours(me, "cf_strain", strain_pct, mesh_object.STRAIN_CLIP_PCT)
        mesh_object.write_colours(me, "cf_warp", warp_deg, mesh_object.WARP_CLIP_DEG)
        return ob

    def summary(self) -> str:
        text = f"baked {len(self.frames)} frames in {self.ms:.0f} ms ({self.iterations} solver iterations)"
        if self.unconverged:
            text += f"; not converged at frames {self.unconverged[:5]}{'...' if len(self.unconverged) > 5 else ''}"
        return text


class CURVED_FOLD_OT_bake(bpy.types.Operator):
    """Bake the fold over the scene's frame range to shape keys"""

    bl_idname = "curved_fold.bake"
    bl_label = "Bake Fold Animation"
    bl_description = (
        "Fold the active mesh frame by frame over the scene's frame range (keyframed Fold Percent, or 0 to the "
        "set percent) and store one keyed shape key per frame; Esc cancels and leaves the object unchanged"
    )
    bl_options = {"REGISTER", "UNDO"}

    _timer = None
    _job: BakeJob | None = None

    @classmethod
    def poll(cls, context):
        return _common.poll_fold_object(cls, context)

    def _new_job(self, context) -> BakeJob:
        scene = context.scene
        return BakeJob(context.active_object, list(range(scene.frame_start, scene.frame_end + 1)))

    def execute(self, context):
        try:
            job = self._new_job(context)
            job.step()
            job.write(context.scene)
        except folding.engine_errors() as exc:
            self.report({"ERROR"}, f"Bake of '{context.active_object.name}' failed: {exc}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"'{job.ob_name}': {job.summary()}")
        return {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            self._job = self._new_job(context)
        except folding.engine_errors() as exc:
            self.report({"ERROR"}, f"Bake of '{context.active_object.name}' failed: {exc}")
            return {"CANCELLED"}
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.02, window=context.window)
        wm.progress_begin(0, len(self._job.frames))
        wm.modal_handler_add(self)
        self._status(context)
        return {"RUNNING_MODAL"}

    def _status(self, context) -> None:
        job = self._job
        text = f"Curved Fold: baking '{job.ob_name}' frame {len(job.positions)}/{len(job.frames)} — Esc to cancel"
        if context.workspace is not None:
            context.workspace.status_text_set(text)
        if context.area is not None:
            context.area.header_text_set(text)
        context.window_manager.progress_update(len(job.positions))
        RUNNING[job.ob_name] = job.progress
        for area in context.screen.areas if context.screen is not None else ():
            if area.type == "VIEW_3D":
                area.tag_redraw()

    def _finish(self, context) -> None:
        if self._job is not None:
            RUNNING.pop(self._job.ob_name, None)
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        if context.area is not None:
            context.area.header_text_set(None)

    def modal(self, context, event):
        if event.type in {"ESC", "RIGHTMOUSE"}:
            self.cancel(context)
            self.report({"WARNING"}, "Bake cancelled; the object is unchanged")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        try:
            self._job.step(TICK_BUDGET_S)
            self._status(context)
            if not self._job.done:
                return {"RUNNING_MODAL"}
            self._job.write(context.scene)
        except folding.engine_errors() as exc:
            self._finish(context)
            self.report({"ERROR"}, f"Bake of '{self._job.ob_name}' failed: {exc}")
            return {"CANCELLED"}
        self._finish(context)
        self.report({"INFO"}, f"'{self._job.ob_name}': {self._job.summary()}")
        return {"FINISHED"}

    def cancel(self, context):
        self._finish(context)
        self._job = None


class CURVED_FOLD_OT_clear_bake(bpy.types.Operator):
    """Remove the baked shape keys and their keyframes from the active folded mesh"""

    bl_idname = "curved_fold.clear_bake"
    bl_label = "Clear Bake"
    bl_description = "Remove the baked fold animation (shape keys and their keyframes) from the active folded mesh"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _common.poll_fold_object(cls, context) and bool(bake.baked_frames(context.active_object))

    def execute(self, context):
        ob = context.active_object
        n = bake.clear_bake(ob)
        ob.curved_fold_mesh.baked_frames = 0
        self.report({"INFO"}, f"Removed {n} baked frames from '{ob.name}'")
        return {"FINISHED"}


CLASSES = (CURVED_FOLD_OT_bake, CURVED_FOLD_OT_clear_bake)
