"""Export operators: the folded mesh (OBJ, STL, glTF with the baked animation, FOLD with one frame per baked frame,
.blend) through Blender's own exporters or the FOLD writer, with the object's modifiers (Solidify) applied, and the
flat crease pattern as SVG in Origami Simulator's convention (for plotters and laser cutters); plus File ▸ Export
entries. The user's scene is never changed: exports run in a temporary scene (``scene.export``)."""

from __future__ import annotations

from pathlib import Path

import bpy
import numpy as np
from bpy.props import EnumProperty, StringProperty
from bpy_extras.io_utils import ExportHelper

from ..scene import bake, export, folding, mesh_object, source_state
from . import _common

FORMATS = (
    ("GLB", "glTF Binary (.glb)", "Folded mesh; with a bake, morph targets and the fold animation", ".glb"),
    ("OBJ", "Wavefront (.obj)", "Folded mesh at the current frame, with modifiers and flat-pattern UVs", ".obj"),
    ("STL", "STL (.stl)", "Folded mesh at the current frame with modifiers (Solidify), millimetres by default", ".stl"),
    ("FOLD", "FOLD (.fold)", "Crease pattern plus one folded FOLD frame per baked frame (simulated angles)", ".fold"),
    ("BLEND", "Blender (.blend)", "The folded object with its baked shape keys", ".blend"),
)
_EXT = {f[0]: f[3] for f in FORMATS}
_FORMAT_OF = {f[3]: f[0] for f in FORMATS}


def folded_frames(ob: bpy.types.Object) -> tuple[list[int], list[np.ndarray]]:
    """Baked frames of ``ob`` and their positions (mm), or ``([], [current positions])`` without a bake."""
    scale = mesh_object.mm_per_unit()
    me = ob.data
    n = len(me.vertices)
    frames = bake.baked_frames(ob)
    if frames:
        out = []
        for f in frames:
            co = np.empty(3 * n, dtype=np.float32)
            me.shape_keys.key_blocks[bake.key_name(f)].points.foreach_get("co", co)
            out.append(co.reshape(-1, 3).astype(np.float64) * scale)
        return frames, out
    co = np.empty(3 * n, dtype=np.float32)
    me.attributes["position"].data.foreach_get("vector", co)
    return [], [co.reshape(-1, 3).astype(np.float64) * scale]


def current_frame_positions(ob: bpy.types.Object, context) -> np.ndarray:
    """Positions (mm) of ``ob``'s own vertices at the current frame: the shape-key mix (animated values) without
    the modifiers, which the export applies itself (``export.export_folded_file(modifiers_from=ob)``)."""
    me = ob.data
    n = len(me.vertices)
    co = np.empty(3 * n, dtype=np.float32)
    me.attributes["position"].data.foreach_get("vector", co)
    out = co.reshape(-1, 3).astype(np.float64)
    keys = me.shape_keys
    if keys is not None and keys.use_relative and len(keys.key_blocks) > 1:
        evaluated = keys.evaluated_get(context.evaluated_depsgraph_get())

        def key_co(kb) -> np.ndarray:
            buf = np.empty(3 * n, dtype=np.float32)
            kb.points.foreach_get("co", buf)
            return buf.reshape(-1, 3).astype(np.float64)

        out = key_co(keys.reference_key)
        for kb, ev in zip(keys.key_blocks[1:], evaluated.key_blocks[1:], strict=True):
            if not kb.mute and ev.value != 0.0:
                out += ev.value * (key_co(kb) - key_co(kb.relative_key))
    return out * mesh_object.mm_per_unit(context.scene)


class CURVED_FOLD_OT_export_folded(bpy.types.Operator, ExportHelper):
    """Export the active folded mesh (OBJ, STL, glTF, FOLD, .blend)"""

    bl_idname = "curved_fold.export_folded"
    bl_label = "Export Folded Mesh"
    bl_description = (
        "Export the active folded mesh: glTF with the baked animation, OBJ/STL of the current frame, FOLD with one "
        "frame per baked frame, or a .blend with the baked object"
    )
    bl_options = {"REGISTER"}

    filename_ext = ".glb"
    filter_glob: StringProperty(default="*.glb;*.obj;*.stl;*.fold;*.blend", options={"HIDDEN"})
    file_format: EnumProperty(
        name="Format", description="File format to write", items=[f[:3] for f in FORMATS], default="GLB"
    )
    unit: EnumProperty(
        name="Units",
        description="Length unit of STL/OBJ files",
        items=(
            ("AUTO", "Automatic", "Millimetres for STL (what slicers assume), metres for OBJ; glTF is always metres"),
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

    def execute(self, context):
        with _common.object_mode(context):
            return self._export(context)

    def _export(self, context):
        ob = context.active_object
        asked = self.filepath
        typed = _FORMAT_OF.get(Path(self.filepath).suffix.lower())
        if typed is not None and not self.properties.is_property_set("file_format"):
            self.file_format = typed  # a script's filepath="m1.stl" writes STL; a format given wins
        if self._with_suffix() and Path(asked).suffix:  # another extension: say so (it was renamed silently)
            self.report(
                {"WARNING"}, f"'{Path(asked).name}' written as '{Path(self.filepath).name}' ({self.file_format})"
            )
        try:
            mesh = mesh_object.read_fold_mesh(ob)
            frames, positions = folded_frames(ob)
            suffix = _EXT[self.file_format]
            kwargs = {"name": ob.name, "fps": context.scene.render.fps, "modifiers_from": ob}
            if suffix in (".obj", ".stl"):
                positions = [current_frame_positions(ob, context)]
                if self.unit != "AUTO":
                    kwargs["unit"] = self.unit.lower()
            elif suffix == ".fold":
                from ..core.metrics import measures as metrics

                # the solver's unwrapped angles of the last fold start an unbaked frame (a valley past flat is
                # 199°, not −161°); baked frames are followed from the flat sheet
                start = None if frames else mesh_object.simulated_fold_angles(ob)
                kwargs = {"fold_angles": metrics.unwrapped_fold_angles(mesh, positions, start)}
            else:
                kwargs["frame_numbers"] = frames or None
            path = export.export_folded_file(self.filepath, mesh, positions, **kwargs)
        except (*folding.engine_errors(), OSError, ImportError) as exc:
            self.report({"ERROR"}, f"Export of '{ob.name}' failed: {exc}")
            return {"CANCELLED"}
        if frames and bake.is_stale(ob):  # the viewport shows a newer fold than the frames written
            self.report(
                {"WARNING"},
                f"Exported '{ob.name}' ({len(positions)} baked frame(s)) to {path}, but the bake is out of date: "
                "the fold changed since it was baked; bake again to export what the viewport shows",
            )
        elif source_state.sources_changed(ob, context.scene):  # curves edited with Live off since the fold
            self.report(
                {"WARNING"},
                f"Exported '{ob.name}' ({len(positions)} frame(s)) to {path}, but its source curves changed since "
                "the fold: Re-fold (and Bake again) to export them",
            )
        else:
            self.report({"INFO"}, f"Exported '{ob.name}' ({len(positions)} frame(s)) to {path}")
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
