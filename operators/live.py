"""The Live toggle of a folded mesh, and the Cancel button of a running job (a live re-fold has no modal handler to
catch Esc); the live re-fold itself (detect, debounce, re-fold) is :mod:`..scene.live`."""

from __future__ import annotations

import bpy
from bpy.props import StringProperty

from . import _common


class CURVED_FOLD_OT_toggle_live(bpy.types.Operator):
    """Toggle live re-folding of the active folded mesh"""

    bl_idname = "curved_fold.toggle_live"
    bl_label = "Live Re-fold"
    bl_description = "Re-fold the active folded mesh automatically while its crease curves or settings are edited"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _common.poll_fold_object(cls, context, object_mode=False)

    def execute(self, context):
        props = context.active_object.curved_fold_mesh
        props.live = not props.live
        self.report({"INFO"}, f"Live re-fold {'on' if props.live else 'off'} for '{context.active_object.name}'")
        return {"FINISHED"}


class CURVED_FOLD_OT_cancel_job(bpy.types.Operator):
    """Cancel the job running on a folded mesh: the scene is left as it was before it"""

    bl_idname = "curved_fold.cancel_job"
    bl_label = "Cancel"
    bl_description = "Stop the job running on this folded mesh; the scene is left exactly as it was before it"
    bl_options = {"INTERNAL"}

    owner: StringProperty(name="Owner", description="The folded mesh (or new fold) whose job to cancel")

    def execute(self, context):
        from ..scene import jobs

        job = jobs.running_job(self.owner)
        if job is None:
            return {"CANCELLED"}
        jobs.cancel(job)
        self.report({"WARNING"}, f"Cancelled {job.kind} '{job.owner}'; the scene is as it was")
        return {"FINISHED"}


CLASSES = (CURVED_FOLD_OT_toggle_live, CURVED_FOLD_OT_cancel_job)
