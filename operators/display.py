"""Show the strain or warp-angle colors of the active folded mesh in the 3D viewports (Solid mode, Attribute
color), or go back to material colors: one click instead of three viewport settings."""

from __future__ import annotations

import bpy
from bpy.props import EnumProperty

from . import _common

ATTRIBUTES = {"STRAIN": "cf_strain", "WARP": "cf_warp", "CROSSING": "cf_crossing"}


def show_colours(ob: bpy.types.Object, kind: str, screens) -> int:
    """Make ``cf_strain``/``cf_warp`` the active colour attribute of ``ob`` and switch every 3D viewport of
    ``screens`` to Solid + Attribute colour (``kind="NONE"``: back to Material colour). Returns the viewports set."""
    if kind != "NONE":
        name = ATTRIBUTES[kind]
        attr = ob.data.color_attributes.get(name)
        if attr is None:
            raise ValueError(f"'{ob.name}' has no '{name}' colors: fold it first")
        ob.data.color_attributes.active_color = attr
    count = 0
    for screen in screens:
        for area in screen.areas:
            for space in area.spaces:
                if space.type == "VIEW_3D":
                    space.shading.type = "SOLID"
                    space.shading.color_type = "MATERIAL" if kind == "NONE" else "VERTEX"
                    count += 1
    return count


class CURVED_FOLD_OT_show_colours(bpy.types.Operator):
    """Show strain or warp-angle colors of the active folded mesh in the viewport"""

    bl_idname = "curved_fold.show_colours"
    bl_label = "Show Fold Colors"
    bl_description = (
        "Color the active folded mesh by strain (Origami Simulator's map: blue 0 → red 5 %), warp angle "
        "(blue 0° → red 10°) or self-intersection (crossing faces red) in the 3D viewports, or go back to material "
        "colors"
    )
    bl_options = {"REGISTER", "UNDO"}

    kind: EnumProperty(
        name="Colors",
        description="What the viewports color the folded mesh by",
        items=(
            ("STRAIN", "Strain", "Per-vertex strain, Origami Simulator's color map"),
            ("WARP", "Warp Angle", "Per-face warp angle (ruling alignment; the paper's quality measure)"),
            ("CROSSING", "Self-Intersection", "Faces passing through the sheet elsewhere in red, the others in blue"),
            ("NONE", "Material", "Back to material colors"),
        ),
        default="STRAIN",
    )

    @classmethod
    def poll(cls, context):
        return _common.poll_fold_object(cls, context, object_mode=False)

    def execute(self, context):
        ob = context.active_object
        screens = [w.screen for w in context.window_manager.windows if w.screen is not None]
        try:
            n = show_colours(ob, self.kind, screens)
        except ValueError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        shown = "material colors" if self.kind == "NONE" else f"{self.kind.lower()} colors"
        self.report({"INFO"}, f"'{ob.name}': {shown} in {n} viewport(s)")
        return {"FINISHED"}


CLASSES = (CURVED_FOLD_OT_show_colours,)
