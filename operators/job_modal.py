"""The modal/blocking runner the Fold, Re-fold and Bake operators share (the jobs themselves: ``scene.jobs``).

``invoke`` (a click in the interface) starts the job and runs it in slices of about ``jobs.SLICE_MS`` on a window
timer: the viewport shows the sheet folding, the status bar and the sidebar show progress, Esc or right-click
cancels and leaves the scene as it was. ``execute`` (``EXEC_DEFAULT``: scripts, ``blender -b``, and ``invoke``
without a window) runs the same job to its end in one call.
"""

from __future__ import annotations

import bpy

from ..scene import folding, jobs


class JobOperator:
    """Mix-in: subclasses define :meth:`make_job` (one scene-level call returning a ``jobs.Job``) and
    :meth:`done` (report what the job's commit returned)."""

    _timer = None
    _job: jobs.Job | None = None
    failure = "failed"
    own_errors: tuple[type[BaseException], ...] = ()
    """Errors, besides the engine's, that a job of this operator reports with their own message (an export's
    ``OSError``: a full disk, a missing folder), not as "the scene changed while it ran"."""

    def make_job(self, context) -> jobs.Job:  # pragma: no cover - every subclass defines it
        raise NotImplementedError

    def done(self, context, result) -> set[str] | None:  # pragma: no cover - every subclass defines it
        """Report what the job's commit returned; the operator's result if not ``{"FINISHED"}``."""
        raise NotImplementedError

    def _fail(self, exc: BaseException) -> set[str]:
        self.report({"ERROR"}, f"{self.failure}: {exc}")
        return {"CANCELLED"}

    def execute(self, context):
        try:
            jobs.stop_live(context.active_object)  # before make_job snapshots it (a frame job's partial shape)
            job = jobs.start(self.make_job(context))
            result = jobs.run_to_end(job)
        except (*folding.engine_errors(), *self.own_errors) as exc:
            return self._fail(exc)
        return self.done(context, result) or {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        return self.start_modal(context)

    def start_modal(self, context):
        """Start the job in slices on a window timer (``invoke``, or an ``execute`` after a file browser)."""
        try:
            jobs.stop_live(context.active_object)  # before make_job snapshots it (a frame job's partial shape)
            self._job = jobs.start(self.make_job(context))
        except folding.engine_errors() as exc:
            return self._fail(exc)
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.01, window=context.window)
        wm.modal_handler_add(self)
        self._status(context)
        return {"RUNNING_MODAL"}

    def _status(self, context) -> None:
        job = self._job
        text = job.status() + " — Esc to cancel"
        if context.workspace is not None:
            context.workspace.status_text_set(text)
        for area in context.screen.areas if context.screen is not None else ():
            if area.type == "VIEW_3D":
                area.tag_redraw()

    def _end_ui(self, context) -> None:
        if self._timer is not None:
            context.window_manager.event_timer_remove(self._timer)
            self._timer = None
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        for area in context.screen.areas if context.screen is not None else ():
            if area.type == "VIEW_3D":
                area.tag_redraw()

    def modal(self, context, event):
        job = self._job
        if event.type in {"ESC", "RIGHTMOUSE"} and event.value == "PRESS":
            self.cancel(context)
            self.report({"WARNING"}, f"Cancelled {job.kind} '{job.owner}'; the scene is as it was")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if not job.running:  # superseded or cancelled elsewhere
            self._end_ui(context)
            if job.cancel_reason:
                self.report({"WARNING"}, f"Cancelled {job.kind} '{job.owner}': {job.cancel_reason}")
            return {"CANCELLED"}
        try:
            ended = jobs.run_slice(job)
        except Exception as exc:  # noqa: BLE001 - the engine's errors, or the user changed the scene under the job:
            self._end_ui(context)  # one line; the timer and status text removed, the preview restored by run_slice
            reason = str(exc) if isinstance(exc, self.own_errors) else folding.failure_reason(exc)
            return self._fail(RuntimeError(reason))
        if not ended:
            self._status(context)
            return {"RUNNING_MODAL"}
        self._end_ui(context)
        return self.done(context, job.result) or {"FINISHED"}

    def cancel(self, context):
        if self._job is not None:
            jobs.cancel(self._job)
        self._end_ui(context)
