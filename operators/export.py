"""Export operators: the folded mesh (OBJ, STL, glTF with the baked animation, FOLD with one frame per baked frame,
.blend) through Blender's own exporters or the FOLD writer, and the flat crease pattern as SVG in Origami
Simulator's convention (for plotters and laser cutters); plus File ▸ Export entries. The user's scene is never
changed: exports run in a temporary scene (``scene.export``)."""

from __future__ import annotations

from pathlib import Path

import bpy
import numpy as np
from bpy.props import EnumProperty, StringProperty
from bpy_extras.io_utils import ExportHelper

from ..scene import bake, export, folding, mesh_object
from . import _common

FORMATS = (
    ("GLB", "glTF Binary (.glb)", "Folded mesh; with a bake, morph targets and the fold animation", ".glb"),
    ("OBJ", "Wavefront (.obj)", "Folded mesh at the current frame", ".obj"),
    ("STL", "STL (.stl)", "Folded mesh at the current frame (3D printing)", ".stl"),
    ("FOLD", "FOLD (.fold)", "Folded state, one FOLD frame per baked frame, simulated fold angles", ".fold"),
    ("BLEND", "Blender (.blend)", "The folded object with its baked shape keys", ".blend"),
)
_EXT = {f[0]: f[3] for f in FORMATS}


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
    """Evaluated positions (mm) of ``ob`` at the current frame (shape-key mix applied)."""
    ev = ob.evaluated_get(context.evaluated_depsgraph_get())
    co = np.empty(3 * len(ev.data.vertices), dtype=np.float32)
    ev.data.attributes["position"].data.foreach_get("vector", co)
    return co.reshape(-1, 3).astype(np.float64) * mesh_object.mm_per_unit(context.scene)


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

    @classmethod
    def poll(cls, context):
        return _common.poll_fold_object(cls, context, object_mode=False)

    def check(self, context):
        path = Path(self.filepath)
        want = _EXT[self.file_format]
        if path.suffix.lower() != want and path.name:
            self.filepath = str(path.with_suffix(want))
            return True
        return False

    def execute(self, context):
        ob = context.active_object
        self.check(context)
        try:
            mesh = mesh_object.read_fold_mesh(ob)
            frames, positions = folded_frames(ob)
            suffix = _EXT[self.file_format]
            kwargs = {"name": ob.name, "fps": context.scene.render.fps}
            if suffix in (".obj", ".stl"):
                positions = [current_frame_positions(ob, context)]
            elif suffix == ".fold":
                from ..core.metrics import measures as metrics

                kwargs = {"fold_angles": [metrics.fold_angles(mesh, p) for p in positions]}
            else:
                kwargs["frame_numbers"] = frames or None
            path = export.export_folded_file(self.filepath, mesh, positions, **kwargs)
        except (*folding.engine_errors(), OSError, ImportError) as exc:
            self.report({"ERROR"}, f"Export of '{ob.name}' failed: {exc}")
            return {"CANCELLED"}
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

    @classmethod
    def poll(cls, context):
        return CURVED_FOLD_OT_export_folded.poll(context)

    def execute(self, context):
        ob = context.active_object
        try:
            path = export.write_pattern_svg(self.filepath, mesh_object.read_fold_mesh(ob))
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
