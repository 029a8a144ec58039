"""Bake operator: fold the active folded mesh frame by frame over the scene's range and store one shape key per
frame (keyed, so playback and glTF export need no add-on), plus Clear Bake.

The work is ``scene.bake.bake_job`` (one scene call): the fold percent per frame comes from the keyframed Fold
Percent (else a ramp from 0 to the set percent), frames already solved during timeline playback come from the
frame cache, new ones warm-start from the nearest solved frame. From the interface it runs in slices (frame k of n
with the time left in the status bar and the sidebar, Esc cancels and leaves the object as it was); from scripts
it runs to the end in one call. Nothing is written until every frame is computed.
"""

from __future__ import annotations

import bpy

from ..scene import bake, source_state
from . import _common
from .job_modal import JobOperator


class CURVED_FOLD_OT_bake(JobOperator, bpy.types.Operator):
    """Bake the fold over the scene's frame range to shape keys"""

    bl_idname = "curved_fold.bake"
    bl_label = "Bake Fold Animation"
    bl_description = (
        "Fold the active mesh frame by frame over the scene's frame range (keyframed Fold Percent, or 0 to the "
        "set percent) and store one keyed shape key per frame; Esc cancels and leaves the object unchanged"
    )
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _common.poll_fold_object(cls, context)

    def make_job(self, context):
        ob, scene = context.active_object, context.scene
        self.failure = f"Bake of '{ob.name}' failed"
        return bake.bake_job(ob, list(range(scene.frame_start, scene.frame_end + 1)), scene=scene)

    def done(self, context, summary) -> None:
        ob = bpy.data.objects.get(summary.ob_name)
        if ob is not None and source_state.sources_changed(ob, context.scene):
            self.report(
                {"WARNING"},
                f"'{ob.name}': its source curves changed since the fold; the bake folds the mesh as last folded "
                "(Re-fold, then Bake again for the edited curves)",
            )
        self.report({"INFO"}, f"'{summary.ob_name}': {summary.text()}")


class CURVED_FOLD_OT_clear_bake(bpy.types.Operator):
    """Remove the baked shape keys and their keyframes from the active folded mesh"""

    bl_idname = "curved_fold.clear_bake"
    bl_label = "Clear Bake"
    bl_description = "Remove the baked fold animation (shape keys and their keyframes) from the active folded mesh"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        ob = context.active_object
        return _common.poll_fold_object(cls, context) and bool(bake.baked_frames(ob) or bake.is_stale(ob))

    def execute(self, context):
        ob = context.active_object
        n = bake.clear(ob)
        self.report({"INFO"}, f"Removed {n} baked frames from '{ob.name}'")
        return {"FINISHED"}


CLASSES = (CURVED_FOLD_OT_bake, CURVED_FOLD_OT_clear_bake)
