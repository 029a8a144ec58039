"""Pin hooks: an empty per pinned vertex of the active folded mesh, so dragging it moves the pin (issue 17)."""

from __future__ import annotations

import bpy

from ..scene import folding, pins
from . import _common


class CURVED_FOLD_OT_add_pin_hooks(bpy.types.Operator):
    """Add an empty at every vertex of the 'cf_pins' vertex group; moving an empty moves its pinned vertex"""

    bl_idname = "curved_fold.add_pin_hooks"
    bl_label = "Add Pin Hooks"
    bl_description = (
        "Add an empty (a child of the folded mesh) at every vertex of its 'cf_pins' vertex group: the vertex is "
        "pinned to its empty on every re-solve, live while Live is on"
    )
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _common.poll_fold_object(cls, context)

    def execute(self, context):
        ob = context.active_object
        try:
            made = pins.add_pin_hooks(ob, context.scene)
        except folding.engine_errors() as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        self.report({"INFO"}, f"'{ob.name}': {len(made)} pin hook(s) added")
        return {"FINISHED"}


CLASSES = (CURVED_FOLD_OT_add_pin_hooks,)
