"""Sidebar panel "Crease Role": the active curve's crease role and fold angle (Curved Fold tab).

First in the tab, as roles come first in the work (import or draw, set roles, fold); the Fold panel
(``fold_panel.py``) follows.
"""

from __future__ import annotations

import math

import bpy

from ._sidebar import SidebarPanel


class VIEW3D_PT_curved_fold_crease_role(SidebarPanel, bpy.types.Panel):
    """Crease role and fold angle of the active curve object"""

    bl_label = "Crease Role"
    bl_order = 0

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        ob = context.active_object
        return ob is not None and ob.type == "CURVE"

    def draw(self, context: bpy.types.Context) -> None:
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        props = context.active_object.curved_fold
        layout.prop(props, "role")
        row = layout.row()
        row.active = props.role in {"MOUNTAIN", "VALLEY"}
        row.prop(props, "fold_angle")
        sign = {"MOUNTAIN": "−", "VALLEY": "+"}.get(props.role)
        if sign:
            layout.label(text=f"Target fold angle {sign}{math.degrees(props.fold_angle):.4g}°", icon="INFO")
        layout.separator()
        col = layout.column(align=True)
        col.operator_menu_enum(
            "curved_fold.set_crease_role", "role", text="Set Role on Selected", icon="CURVE_BEZCURVE"
        )
        col.operator_menu_enum("curved_fold.select_by_role", "role", text="Select by Role", icon="RESTRICT_SELECT_OFF")


CLASSES = (VIEW3D_PT_curved_fold_crease_role,)
