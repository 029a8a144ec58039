"""Import operator: a crease pattern file (SVG from Origami Simulator or a drawing program, FOLD) becomes editable
Bézier curve objects with their crease roles and angles set, in a new collection; plus File ▸ Import entry."""

from __future__ import annotations

import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ImportHelper

from ..scene import folding, import_curves


class CURVED_FOLD_OT_import_pattern(bpy.types.Operator, ImportHelper):
    """Import a crease pattern (SVG or FOLD) as crease curve objects"""

    bl_idname = "curved_fold.import_pattern"
    bl_label = "Import Crease Pattern"
    bl_description = (
        "Import an SVG (Origami Simulator colours: mountain red, valley blue, opacity = angle/180) or FOLD crease "
        "pattern as Bézier curve objects with crease roles set, ready to edit and fold"
    )
    bl_options = {"REGISTER", "UNDO", "PRESET"}

    filename_ext = ".svg"
    filter_glob: StringProperty(default="*.svg;*.fold", options={"HIDDEN"})

    def execute(self, context):
        try:
            objects, warnings = import_curves.import_crease_pattern(self.filepath, scene=context.scene)
        except (*folding.engine_errors(), OSError) as exc:
            self.report({"ERROR"}, f"Import failed: {exc}")
            return {"CANCELLED"}
        for other in context.selected_objects:
            other.select_set(False)
        for ob in objects:
            ob.select_set(True)
        context.view_layer.objects.active = objects[0]
        for warning in warnings[:5]:
            self.report({"WARNING"}, warning)
        coll = objects[0].users_collection[0].name
        self.report({"INFO"}, f"Imported {len(objects)} crease curves into collection '{coll}'")
        return {"FINISHED"}


def _menu_import(self, context):
    self.layout.operator(CURVED_FOLD_OT_import_pattern.bl_idname, text="Crease Pattern (.svg/.fold)")


CLASSES = (CURVED_FOLD_OT_import_pattern,)


def register_extra() -> None:
    bpy.types.TOPBAR_MT_file_import.append(_menu_import)


def unregister_extra() -> None:
    bpy.types.TOPBAR_MT_file_import.remove(_menu_import)
