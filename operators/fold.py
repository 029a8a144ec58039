"""Fold and Re-fold operators: crease curves → ruling-aware mesh → folded mesh object (source curves untouched).

Both run as jobs (``job_modal``): in slices with progress and Esc from the interface, blocking from scripts."""

from __future__ import annotations

import math

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, StringProperty

from ..scene import folding
from ..scene.fold_settings import MESH_TYPES
from . import _common
from .job_modal import JobOperator


class CURVED_FOLD_OT_fold(JobOperator, bpy.types.Operator):
    """Build the ruling-aware mesh from the selected crease curves (or a collection) and fold it"""

    bl_idname = "curved_fold.fold"
    bl_label = "Fold Crease Pattern"
    bl_description = (
        "Triangulate the selected crease curves (or the chosen collection) with ruling-aware edge swaps and fold "
        "the result into a new mesh object beside them; the curves are not changed"
    )
    bl_options = {"REGISTER", "UNDO"}
    failure = "Fold failed"

    collection: StringProperty(
        name="Collection", description="Fold the crease curves of this collection instead of the selection"
    )
    interval: FloatProperty(
        name="Interval",
        description="Largest chord length of curves, borders and split straight creases (0 = automatic)",
        default=0.0,
        min=0.0,
        subtype="DISTANCE",
        unit="LENGTH",
    )
    tolerance: FloatProperty(
        name="Tolerance",
        description="Largest curve-to-chord distance (0 = automatic)",
        default=0.0,
        min=0.0,
        subtype="DISTANCE",
        unit="LENGTH",
    )
    mesh_type: EnumProperty(
        name="Mesh", description="How the crease pattern is triangulated", items=MESH_TYPES, default="RULING"
    )
    use_fold_angle: BoolProperty(
        name="Override Crease Angles",
        description="Fold every mountain and valley crease to Fold Angle, whatever angle its curve has",
        default=False,
    )
    fold_angle: FloatProperty(
        name="Fold Angle",
        description="Fold angle of every mountain/valley crease when Override Crease Angles is on",
        default=math.pi,
        min=0.0,
        max=math.pi,
        subtype="ANGLE",
        unit="ROTATION",
    )
    fold_percent: FloatProperty(
        name="Fold Percent", default=100.0, min=0.0, max=100.0, subtype="PERCENTAGE", description="How far to fold"
    )
    solver: EnumProperty(
        name="Solver",
        description="Which solver folds the mesh",
        items=(("FAST", "Fast", "Solve to equilibrium (default)"), ("FAITHFUL", "Faithful", "Origami Simulator's")),
        default="FAST",
    )

    @classmethod
    def poll(cls, context):
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode")
            return False
        # poll cannot see the operator's options, so a script folding a `collection` with nothing selected must
        # pass: any crease curve in the file will do; execute() names a missing selection or collection.
        if not folding.curve_objects(context.selected_objects or []) and not folding.curve_objects(bpy.data.objects):
            cls.poll_message_set("Select crease curve objects (curves with a crease role)")
            return False
        return True

    def _sources(self, context):
        if self.collection:
            coll = bpy.data.collections.get(self.collection)
            if coll is None:
                raise folding.PatternError(f"no collection named '{self.collection}'")
            return coll, folding.shown_crease_curves(coll)[0]
        return None, folding.curve_objects(context.selected_objects or [])

    def make_job(self, context):
        coll, sources = self._sources(context)
        options = folding.FoldOptions(
            interval=self.interval,
            tolerance=self.tolerance,
            mesh_type=self.mesh_type,
            use_fold_angle=self.use_fold_angle,
            fold_angle=self.fold_angle,
            fold_percent=self.fold_percent,
            solver=self.solver,
        )
        return folding.fold_job(sources, coll, options, scene=context.scene)

    def done(self, context, result) -> None:
        ob, out = result
        if context.view_layer.objects.get(ob.name) is ob:
            for other in context.selected_objects:
                other.select_set(False)
            ob.select_set(True)
            context.view_layer.objects.active = ob
        else:  # made beside its curves, in a collection excluded from the view layer: not selectable (a traceback)
            self.report(
                {"WARNING"}, f"'{ob.name}' is in a collection excluded from the view layer: include it to see it"
            )
        for warning in out.warnings[:5]:
            self.report({"WARNING"}, warning)
        props = ob.curved_fold_mesh
        if props.last_message:
            self.report({"WARNING"}, f"'{ob.name}' {props.last_message}")
        self.report({"INFO"}, f"Folded '{ob.name}': {folding.figures_text(props)}")


class CURVED_FOLD_OT_refold(JobOperator, bpy.types.Operator):
    """Fold the active folded mesh again from its source curves and current settings"""

    bl_idname = "curved_fold.refold"
    bl_label = "Re-fold"
    bl_description = (
        "Rebuild the active folded mesh from its source crease curves (or re-solve its stored mesh if the curves "
        "are gone) with the current settings; clears any bake"
    )
    bl_options = {"REGISTER", "UNDO"}

    rebuild: EnumProperty(
        name="Rebuild",
        description="Rebuild the mesh from the source curves, or only solve the stored mesh again",
        items=(
            ("AUTO", "Auto", "Rebuild from the source curves when they exist, else re-solve the stored mesh"),
            ("REBUILD", "Rebuild", "Always rebuild the mesh from the source curves"),
            ("RESOLVE", "Re-solve", "Keep the mesh, only solve again (fold percent, solver settings)"),
        ),
        default="AUTO",
    )

    @classmethod
    def poll(cls, context):
        return _common.poll_fold_object(cls, context)

    def make_job(self, context):
        rebuild = {"AUTO": None, "REBUILD": True, "RESOLVE": False}[self.rebuild]
        self.failure = f"Re-fold of '{context.active_object.name}' failed"
        return folding.refold_job(context.active_object, rebuild=rebuild, scene=context.scene)

    def done(self, context, out) -> None:
        ob = context.active_object
        props = ob.curved_fold_mesh
        if props.last_message:
            self.report({"WARNING"}, f"'{ob.name}' {props.last_message}")
        self.report({"INFO"}, f"Re-folded '{ob.name}': {folding.figures_text(props)}")


CLASSES = (CURVED_FOLD_OT_fold, CURVED_FOLD_OT_refold)
