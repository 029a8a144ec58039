"""Import operator: a crease pattern file (SVG from Origami Simulator or a drawing program, FOLD) becomes a handful
of editable curve objects (one per role and fold angle) in a new collection; plus the File ▸ Import entry and a
``FileHandler`` so .svg/.fold files dropped on the 3D viewport are imported the same way."""

from __future__ import annotations

import os

import bpy
from bpy.props import BoolProperty, CollectionProperty, StringProperty
from bpy_extras.io_utils import ImportHelper, poll_file_object_drop

from ..scene import import_curves
from .job_modal import JobOperator


class CURVED_FOLD_OT_import_pattern(JobOperator, bpy.types.Operator, ImportHelper):
    """Import a crease pattern (SVG or FOLD) as crease curve objects"""

    bl_idname = "curved_fold.import_pattern"
    bl_label = "Import Crease Pattern"
    bl_description = (
        "Import an SVG (Origami Simulator colors: mountain red, valley blue, opacity = angle/180) or FOLD crease "
        "pattern as curve objects, one per crease role and fold angle, ready to edit and fold"
    )
    bl_options = {"REGISTER", "UNDO", "PRESET"}
    failure = "Import failed"

    filename_ext = ".svg"
    filter_glob: StringProperty(default="*.svg;*.fold", options={"HIDDEN"})
    directory: StringProperty(subtype="DIR_PATH", options={"SKIP_SAVE", "HIDDEN"})
    files: CollectionProperty(
        name="Files",
        description="Crease pattern files to import (several may be chosen or dropped)",
        type=bpy.types.OperatorFileListElement,
        options={"SKIP_SAVE"},
    )

    browsed: BoolProperty(
        name="From the File Browser",
        description="Chosen in the file browser: import as a job in slices (Esc cancels), not in one call",
        default=False,
        options={"HIDDEN", "SKIP_SAVE"},
    )

    def invoke(self, context, event):
        if self.properties.is_property_set("filepath") or self.files:  # a dropped file: no file browser
            return JobOperator.invoke(self, context, event)
        self.browsed = True
        return ImportHelper.invoke(self, context, event)

    def execute(self, context):
        if self.browsed and not bpy.app.background and context.window is not None:
            return self.start_modal(context)  # after the file browser: in slices, as a dropped file
        return JobOperator.execute(self, context)

    def _paths(self) -> list[str]:
        names = [f.name for f in self.files if f.name]
        if names and self.directory:
            return [os.path.join(self.directory, name) for name in names]
        return [self.filepath]

    def make_job(self, context):
        return import_curves.import_job(self._paths(), scene=context.scene)

    def done(self, context, result):
        imported, error = result
        made: list[bpy.types.Object] = []
        for path, objects, warnings in imported:
            made.extend(objects)
            for warning in warnings[:5]:
                self.report({"WARNING"}, warning)
            coll = objects[0].users_collection[0].name
            self.report({"INFO"}, f"Imported {os.path.basename(path)} as {len(objects)} curve object(s) in '{coll}'")
        if error is not None:
            self.report({"ERROR"}, f"Import failed: {error}")
        if not made:
            return {"CANCELLED"}
        for other in context.selected_objects:
            other.select_set(False)
        for ob in made:
            ob.select_set(True)
        context.view_layer.objects.active = made[0]
        return {"FINISHED"}


class CURVED_FOLD_FH_crease_pattern(bpy.types.FileHandler):
    """Drag and drop .svg and .fold files on the 3D viewport: imported as crease patterns"""

    bl_idname = "CURVED_FOLD_FH_crease_pattern"
    bl_label = "Crease Pattern (Curved Fold)"
    bl_import_operator = CURVED_FOLD_OT_import_pattern.bl_idname
    bl_file_extensions = ".svg;.fold"

    @classmethod
    def poll_drop(cls, context):
        return poll_file_object_drop(context)


def _menu_import(self, context):
    self.layout.operator(CURVED_FOLD_OT_import_pattern.bl_idname, text="Crease Pattern (.svg/.fold)")


CLASSES = (CURVED_FOLD_OT_import_pattern, CURVED_FOLD_FH_crease_pattern)


def register_extra() -> None:
    bpy.types.TOPBAR_MT_file_import.append(_menu_import)


def unregister_extra() -> None:
    bpy.types.TOPBAR_MT_file_import.remove(_menu_import)
