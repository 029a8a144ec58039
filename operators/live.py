"""The Live toggle of a folded mesh; the live re-fold itself (detect, debounce, re-fold) is :mod:`..scene.live`."""

from __future__ import annotations

import bpy

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


CLASSES = (CURVED_FOLD_OT_toggle_live,)
