"""Export operators: the folded mesh (OBJ, STL, glTF with the baked animation, FOLD with one frame per baked frame,
.blend) through Blender's own exporters or the FOLD writer, with the object's modifiers (Solidify) applied, and the
flat crease pattern as SVG in Origami Simulator's convention (for plotters and laser cutters); plus File ▸ Export
entries. The user's scene is never changed: exports run in a temporary scene (``scene.export``)."""

from __future__ import annotations

from pathlib import Path

import bpy
from bpy.props import BoolProperty, EnumProperty, StringProperty
from bpy_extras.io_utils import ExportHelper

from ..scene import bake, export, folding, mesh_object, source_state, timeline
from . import _common
from .job_modal import JobOperator

FORMATS = (
    ("GLB", "glTF Binary (.glb)", "Folded mesh; with a bake, morph targets and the fold animation", ".glb"),
    (
        "GLTF",
        "glTF Embedded (.gltf)",
        "The same as glTF Binary, as one JSON text file with its data embedded (for web viewers and text tools)",
        ".gltf",
    ),
    ("OBJ", "Wavefront (.obj)", "Folded mesh at the current frame, with modifiers and flat-pattern UVs", ".obj"),
    ("STL", "STL (.stl)", "Folded mesh at the current frame with modifiers (Solidify), millimetres by default", ".stl"),
    ("FOLD", "FOLD (.fold)", "Crease pattern plus one folded FOLD frame per baked frame (simulated angles)", ".fold"),
    ("BLEND", "Blender (.blend)", "The folded object with its baked shape keys", ".blend"),
)
_EXT = {f[0]: f[3] for f in FORMATS}
_FORMAT_OF = {f[3]: f[0] for f in FORMATS}


class CURVED_FOLD_OT_export_folded(JobOperator, bpy.types.Operator, ExportHelper):
    """Export the active folded mesh (OBJ, STL, glTF, FOLD, .blend).

    From the file browser it runs as a job in slices (``scene.export.export_job``, the ``JobOperator`` pattern):
    progress in the status bar and the sidebar, Esc cancels and leaves the scene and the files as they were. A script
    (``execute``) runs the same job to its end in one call, writing the same bytes. Every unit of work stays well
    within ``jobs.SLICE_MS`` except one: Blender's own exporter (glTF, OBJ, STL, the .blend write) is a single call that
    cannot be split, run in a slice of its own. Measured at 3,000 faces with 60 baked frames (docs/benchmarks.md):
    the glTF exporter's unit takes ~180 ms wall, ~300 ms CPU (it uses threads; with a Solidify modifier ~230 ms
    wall), the OBJ/STL/.blend ones 4-9 ms. FOLD is written by the add-on in units of a frame: its longest unit is
    reading the flat pattern back, ~35 ms; its slices stay within the budget."""

    bl_idname = "curved_fold.export_folded"
    bl_label = "Export Folded Mesh"
    bl_description = (
        "Export the active folded mesh: glTF with the baked animation, OBJ/STL of the current frame, FOLD with one "
        "frame per baked frame, or a .blend with the baked object"
    )
    bl_options = {"REGISTER"}
    own_errors = (OSError, ImportError)

    filename_ext = ".glb"
    filter_glob: StringProperty(default="*.glb;*.gltf;*.obj;*.stl;*.fold;*.blend", options={"HIDDEN"})
    file_format: EnumProperty(
        name="Format", description="File format to write", items=[f[:3] for f in FORMATS], default="GLB"
    )
    unit: EnumProperty(
        name="Units",
        description="Length unit of STL/OBJ files",
        items=(
            (
                "AUTO",
                "Automatic",
                "Millimetres for STL (what slicers assume); OBJ in the scene's unit (millimetres in a scene of 1 "
                "unit = 1 mm, else metres), as Blender's OBJ exporter writes it; glTF is always metres",
            ),
            ("MM", "Millimetres", "STL/OBJ lengths in millimetres"),
            ("M", "Metres", "STL/OBJ lengths in metres (Blender units)"),
        ),
        default="AUTO",
    )

    @classmethod
    def poll(cls, context):
        return _common.poll_fold_object(cls, context, object_mode=False)

    shown_format: StringProperty(options={"HIDDEN", "SKIP_SAVE"})
    """The format :meth:`check` last saw, to tell a change of the Format menu from a typed file extension."""

    def check(self, context):
        """Keep the file name and the format together: a typed extension of another format chooses that format
        (``m1.stl`` writes STL, as the name says; it wrote ``m1.glb``), a change of the Format menu renames."""
        typed = _FORMAT_OF.get(Path(self.filepath).suffix.lower())
        switched = typed is not None and typed != self.file_format and self.shown_format in ("", self.file_format)
        if switched:
            self.file_format = typed
        self.shown_format = self.file_format
        return self._with_suffix() or switched

    def _with_suffix(self) -> bool:
        """Give the file name the format's extension; whether it changed."""
        path = Path(self.filepath)
        want = _EXT[self.file_format]
        if path.suffix.lower() != want and path.name:
            self.filepath = str(path.with_suffix(want))
            return True
        return False

    browsed: BoolProperty(
        name="From the File Browser",
        description="Chosen in the file browser: export as a job in slices (Esc cancels), not in one call",
        default=False,
        options={"HIDDEN", "SKIP_SAVE"},
    )

    _reedit = ""
    """The object that was in Edit Mode when the modal job started: back in it when the job ends."""

    def invoke(self, context, event):
        self.browsed = True
        return ExportHelper.invoke(self, context, event)

    def execute(self, context):
        timeline.finish_frame_job(context.active_object)  # the frame the timeline is on, not the one before it
        self._choose_format()
        if self.browsed and not bpy.app.background and context.window is not None:
            ob = context.active_object
            self._reedit = ob.name if ob.mode == "EDIT" else ""  # the job reads the mesh's arrays, empty there
            if self._reedit:
                bpy.ops.object.mode_set(mode="OBJECT")
            result = self.start_modal(context)  # after the file browser: in slices, as Fold and Bake
            if "RUNNING_MODAL" not in result:
                self._back_to_edit_mode(context)
            return result
        with _common.object_mode(context):
            return JobOperator.execute(self, context)

    def _choose_format(self) -> None:
        """The format from a typed extension (unless given), the file name given the format's extension."""
        asked = self.filepath
        typed = _FORMAT_OF.get(Path(self.filepath).suffix.lower())
        if typed is not None and not self.properties.is_property_set("file_format"):
            self.file_format = typed  # a script's filepath="m1.stl" writes STL; a format given wins
        if self._with_suffix() and Path(asked).suffix:  # another extension: say so (it was renamed silently)
            self.report(
                {"WARNING"}, f"'{Path(asked).name}' written as '{Path(self.filepath).name}' ({self.file_format})"
            )

    def make_job(self, context):
        ob = context.active_object
        self.failure = f"Export of '{ob.name}' failed"
        if self.file_format in ("OBJ", "STL") and self.unit != "AUTO":
            unit = self.unit.lower()
        else:
            unit = export.automatic_unit(self.filepath, context.scene)
        return export.export_job(ob, self.filepath, unit=unit, scene=context.scene)

    def _end_ui(self, context) -> None:
        JobOperator._end_ui(self, context)
        self._back_to_edit_mode(context)

    def _back_to_edit_mode(self, context) -> None:
        ob = context.active_object
        if self._reedit and ob is not None and ob.name == self._reedit and ob.mode == "OBJECT":
            bpy.ops.object.mode_set(mode="EDIT")
        self._reedit = ""

    def done(self, context, result):
        ob = bpy.data.objects.get(self._job.owner) if self._job is not None else context.active_object
        name, n, path = (ob.name if ob is not None else "?"), result.n_frames, result.path
        if ob is not None and result.baked and bake.is_stale(ob):  # the viewport shows a newer fold than written
            self.report(
                {"WARNING"},
                f"Exported '{name}' ({n} baked frame(s)) to {path}, but the bake is out of date: "
                "the fold changed since it was baked; bake again to export what the viewport shows",
            )
        elif ob is not None and source_state.sources_changed(ob, context.scene):  # curves edited with Live off
            self.report(
                {"WARNING"},
                f"Exported '{name}' ({n} frame(s)) to {path}, but its source curves changed since "
                "the fold: Re-fold (and Bake again) to export them",
            )
        else:
            self.report({"INFO"}, f"Exported '{name}' ({n} frame(s)) to {path}")
        return {"FINISHED"}


class CURVED_FOLD_OT_export_pattern_svg(bpy.types.Operator, ExportHelper):
    """Export the flat crease pattern of the active folded mesh as SVG (Origami Simulator colours)"""

    bl_idname = "curved_fold.export_pattern_svg"
    bl_label = "Export Crease Pattern SVG"
    bl_description = (
        "Write the flat crease pattern as SVG in millimetres: border black, mountain red, valley blue, facet "
        "yellow, undriven magenta, cut green, opacity = |fold angle| / 180 (Origami Simulator's convention)"
    )
    bl_options = {"REGISTER"}

    filename_ext = ".svg"
    filter_glob: StringProperty(default="*.svg", options={"HIDDEN"})
    layout: EnumProperty(
        name="Layout",
        description="How the flat pattern is drawn: for Origami Simulator (reads back), or in layers for a cutter",
        items=(
            ("ORIGAMI_SIMULATOR", "Origami Simulator", "Every role in its colour, opacity = fold angle (reads back)"),
            ("CUTTER", "Cutter Layers", "A 'cut' layer (border, cuts; hairline) and a 'score' layer (creases)"),
        ),
        default="ORIGAMI_SIMULATOR",
    )

    @classmethod
    def poll(cls, context):
        return CURVED_FOLD_OT_export_folded.poll(context)

    def execute(self, context):
        ob = context.active_object
        if Path(self.filepath).suffix.lower() != ".svg":  # a script's filepath without it (the browser adds it)
            if Path(self.filepath).suffix:
                self.report({"WARNING"}, f"'{Path(self.filepath).name}' written as '{Path(self.filepath).name}.svg'")
            self.filepath += ".svg"
        try:
            layout = "cutter" if self.layout == "CUTTER" else "origami-simulator"
            with _common.object_mode(context):
                mesh = mesh_object.read_fold_mesh(ob)
            path = export.write_pattern_svg(self.filepath, mesh, layout=layout)
        except (*folding.engine_errors(), OSError) as exc:
            self.report({"ERROR"}, f"SVG export of '{ob.name}' failed: {exc}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Wrote the crease pattern of '{ob.name}' to {path}")
        return {"FINISHED"}


def _menu_export(self, context):
    self.layout.operator(CURVED_FOLD_OT_export_folded.bl_idname, text="Folded Mesh (Curved Fold)")
    self.layout.operator(CURVED_FOLD_OT_export_pattern_svg.bl_idname, text="Crease Pattern (.svg, Curved Fold)")


CLASSES = (CURVED_FOLD_OT_export_folded, CURVED_FOLD_OT_export_pattern_svg)


def register_extra() -> None:
    bpy.types.TOPBAR_MT_file_export.append(_menu_export)


def unregister_extra() -> None:
    bpy.types.TOPBAR_MT_file_export.remove(_menu_export)
