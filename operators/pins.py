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


class CURVED_FOLD_OT_glue_selected(bpy.types.Operator):
    """Glue the two selected vertices of the folded mesh together (a zero-length bar on every re-solve)"""

    bl_idname = "curved_fold.glue_selected"
    bl_label = "Glue Selected"
    bl_description = (
        "Glue the two vertices selected in Edit Mode: every re-solve pulls them together with a zero-length bar "
        "(Last Run shows the gap left)"
    )
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.mode != "EDIT_MESH":
            cls.poll_message_set("Select the two vertices to glue in Edit Mode")
            return False
        return _common.poll_fold_object(cls, context, object_mode=False)

    def execute(self, context):
        import bmesh

        ob = context.active_object
        selected = [v.index for v in bmesh.from_edit_mesh(ob.data).verts if v.select]
        if len(selected) != 2:
            self.report({"ERROR"}, f"select exactly two vertices to glue ({len(selected)} selected)")
            return {"CANCELLED"}
        count = pins.add_glue_pair(ob, *selected)
        self.report({"INFO"}, f"'{ob.name}': vertices {selected[0]} and {selected[1]} glued ({count} picked pairs)")
        return {"FINISHED"}


class CURVED_FOLD_OT_clear_glue(bpy.types.Operator):
    """Forget the glue pairs picked with Glue Selected (the cf_glue_a/cf_glue_b vertex groups stay)"""

    bl_idname = "curved_fold.clear_glue"
    bl_label = "Clear Picked Glue"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _common.poll_fold_object(cls, context, object_mode=False)

    def execute(self, context):
        context.active_object.pop(pins.PAIRS_KEY, None)
        return {"FINISHED"}


CLASSES = (CURVED_FOLD_OT_add_pin_hooks, CURVED_FOLD_OT_glue_selected, CURVED_FOLD_OT_clear_glue)
