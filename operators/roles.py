"""Give selected curve objects a crease role and fold angle, and select curves by role.

Thin operators over :mod:`..scene.properties`: the role and angle are stored on the object
(``Object.curved_fold``); the colours follow from the role's update callback (:mod:`..scene.role_display`).
"""

from __future__ import annotations

import math

import bpy

from ..scene.properties import ROLE_ITEMS

_ANGLE_ROLES = {"MOUNTAIN", "VALLEY"}


class CURVED_FOLD_OT_set_crease_role(bpy.types.Operator):
    """Set the crease role of the selected curve objects; each keeps its fold angle unless one is given"""

    bl_idname = "curved_fold.set_crease_role"
    bl_label = "Set Crease Role"
    bl_description = (
        "Give the selected curve objects a crease role (border, mountain, valley, facet, undriven, cut); each keeps "
        "its own fold angle unless Set Fold Angle is on. The curves are colored as Origami Simulator draws them, "
        "through the object's material slots and color: their own materials stay, and None puts their look back"
    )
    bl_options = {"REGISTER", "UNDO"}

    role: bpy.props.EnumProperty(name="Role", description="Crease role to give the curves", items=ROLE_ITEMS)
    use_fold_angle: bpy.props.BoolProperty(
        name="Set Fold Angle",
        description="Also give the curves this fold angle; off, every curve keeps its own angle",
        default=False,
    )
    fold_angle: bpy.props.FloatProperty(
        name="Fold Angle",
        description="Target fold angle (0° flat, 180° folded flat) given to every selected curve when Set Fold "
        "Angle is on (or this value is passed); mountains fold away from +Z, valleys towards it",
        default=math.pi,
        min=0.0,
        max=math.pi,
        precision=1,
        subtype="ANGLE",
        unit="ROTATION",
    )

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        if not any(ob.type == "CURVE" for ob in (context.selected_objects or ())):
            cls.poll_message_set("Select one or more curve objects")
            return False
        return True

    def draw(self, context: bpy.types.Context) -> None:
        layout = self.layout
        layout.prop(self, "role")
        row = layout.row(heading="Set Fold Angle")
        row.active = self.role in _ANGLE_ROLES
        row.prop(self, "use_fold_angle", text="")
        sub = row.row()
        sub.active = self.use_fold_angle
        sub.prop(self, "fold_angle")

    def _sets_angle(self) -> bool:
        """An angle was asked for: the option is on, or a script passed ``fold_angle``. Otherwise angles stay."""
        return self.role in _ANGLE_ROLES and (self.use_fold_angle or self.properties.is_property_set("fold_angle"))

    def execute(self, context: bpy.types.Context) -> set[str]:
        curves = [ob for ob in context.selected_objects if ob.type == "CURVE"]
        others = len(context.selected_objects) - len(curves)
        if not curves:
            self.report({"ERROR"}, "No curve objects selected: crease roles apply to curve objects only")
            return {"CANCELLED"}
        sets_angle = self._sets_angle()
        for ob in curves:
            if sets_angle:
                ob.curved_fold.fold_angle = self.fold_angle
            ob.curved_fold.role = self.role
        label = dict((item[0], item[1]) for item in ROLE_ITEMS)[self.role]
        angle = f" ({math.degrees(self.fold_angle):.4g}°)" if sets_angle else ""
        message = f"Crease role {label}{angle} set on {len(curves)} curve(s)"
        if others:
            message += f"; {others} non-curve object(s) left unchanged"
        self.report({"INFO"}, message)
        return {"FINISHED"}


class CURVED_FOLD_OT_select_by_role(bpy.types.Operator):
    """Select the curve objects that have a given crease role"""

    bl_idname = "curved_fold.select_by_role"
    bl_label = "Select Curves by Crease Role"
    bl_description = "Select the visible curve objects with the given crease role"
    bl_options = {"REGISTER", "UNDO"}

    role: bpy.props.EnumProperty(name="Role", description="Crease role to select", items=ROLE_ITEMS, default="VALLEY")
    extend: bpy.props.BoolProperty(name="Extend", description="Add to the current selection", default=False)

    def execute(self, context: bpy.types.Context) -> set[str]:
        view_layer = context.view_layer
        count = 0
        for ob in view_layer.objects:
            match = ob.type == "CURVE" and ob.curved_fold.role == self.role and ob.visible_get(view_layer=view_layer)
            if match:
                ob.select_set(True, view_layer=view_layer)
                count += 1
            elif not self.extend:
                ob.select_set(False, view_layer=view_layer)
        self.report({"INFO"}, f"{count} curve(s) with crease role {self.role.title()} selected")
        return {"FINISHED"}


CLASSES = (CURVED_FOLD_OT_set_crease_role, CURVED_FOLD_OT_select_by_role)
