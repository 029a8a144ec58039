"""Sidebar panels (Curved Fold tab) for folding: the Fold button for selected crease curves, and for a folded mesh
its pattern parameters, fold angle and percent (keyframable), solver settings, Re-fold / Live / Bake / Export, the
last run's figures and the "does not fold as assigned" message. Drawing only: no numerics here."""

from __future__ import annotations

import bpy

from ._sidebar import SidebarPanel


def _fold_props(context):
    ob = context.active_object
    props = getattr(ob, "curved_fold_mesh", None) if ob is not None else None
    return props if props is not None and props.is_fold_mesh else None


def _sources_changed(context) -> bool:
    """Whether the active fold object's source curves changed since its mesh was built (cached by the scene
    module, so drawing stays cheap)."""
    from ..scene.source_state import sources_changed

    return sources_changed(context.active_object, context.scene)


def _job_progress(layout, name: str) -> None:
    """Progress row of the job running on the fold object ``name`` (iteration and residual, or frame k of n) with
    its Cancel button: a live re-fold runs on a timer, without the modal handler that catches Esc, and the row said
    "Esc cancels" for it too (a designer session)."""
    from ..scene.jobs import running_job

    job = running_job(name)
    if job is None:
        return
    hint = "" if job.live else " (Esc cancels)"
    text = f"{job.kind.capitalize()}: {job.progress.text(job.elapsed_ms / 1e3)}{hint}"
    row = layout.row(align=True)
    if hasattr(row, "progress"):  # UILayout.progress: Blender 4.0+
        row.progress(factor=job.progress.fraction, type="BAR", text=text)
    else:  # pragma: no cover
        row.label(text=text, icon="TIME")
    row.operator("curved_fold.cancel_job", text="", icon="CANCEL").owner = name


class VIEW3D_PT_curved_fold_fold(SidebarPanel, bpy.types.Panel):
    """Fold the selected crease curves"""

    bl_label = "Fold"
    bl_order = 10

    @classmethod
    def poll(cls, context):
        return _fold_props(context) is None

    def draw(self, context):
        layout = self.layout
        curves = [ob for ob in context.selected_objects if ob.type == "CURVE"]
        layout.label(text=f"{len(curves)} curve(s) selected", icon="CURVE_BEZCURVE")
        from ..scene import jobs

        for owner, job in list(jobs._jobs.items()):
            if job.kind == "folding":
                _job_progress(layout, owner)
        layout.operator("curved_fold.fold", icon="MOD_SIMPLEDEFORM")
        layout.operator("curved_fold.import_pattern", icon="IMPORT")


class VIEW3D_PT_curved_fold_mesh(SidebarPanel, bpy.types.Panel):
    """Settings and figures of the active folded mesh"""

    bl_label = "Folded Mesh"
    bl_order = 20

    @classmethod
    def poll(cls, context):
        return _fold_props(context) is not None

    def draw(self, context):
        layout = self.layout
        props = _fold_props(context)
        layout.use_property_split = True
        layout.use_property_decorate = True  # the keyframe dot: Fold Percent animates the fold
        _job_progress(layout, context.active_object.name)
        col = layout.column()
        col.prop(props, "fold_percent", slider=True)
        row = col.row(align=True)
        row.prop(props, "use_fold_angle")
        sub = row.row()
        sub.active = props.use_fold_angle
        sub.prop(props, "fold_angle", text="")
        row = layout.row(align=True)
        row.scale_y = 1.3
        row.operator("curved_fold.refold", icon="FILE_REFRESH")
        row.prop(props, "live", toggle=True, icon="REC" if props.live else "RADIOBUT_OFF")
        if _sources_changed(context):
            box = layout.box()
            box.alert = True
            box.label(text="Source curves changed since the fold: Re-fold", icon="ERROR")
        if props.last_message:
            box = layout.box()
            box.alert = True
            for i in range(0, len(props.last_message), 60):
                box.label(text=props.last_message[i : i + 60], icon="ERROR" if i == 0 else "BLANK1")


class VIEW3D_PT_curved_fold_pattern(SidebarPanel, bpy.types.Panel):
    bl_label = "Pattern"
    bl_parent_id = "VIEW3D_PT_curved_fold_mesh"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        props = _fold_props(context)
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(props, "mesh_type")
        layout.prop(props, "interval")
        layout.prop(props, "tolerance")
        layout.prop(props, "source_collection")
        layout.label(text=f"{len(props.sources)} source curve(s)")


class VIEW3D_PT_curved_fold_solver(SidebarPanel, bpy.types.Panel):
    bl_label = "Solver"
    bl_parent_id = "VIEW3D_PT_curved_fold_mesh"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        props = _fold_props(context)
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(props, "solver")
        layout.prop(props, "isometric")
        col = layout.column(align=True, heading="Stiffness")
        for name in ("axial_stiffness", "crease_stiffness", "panel_stiffness", "face_stiffness", "damping"):
            col.prop(props, name)


class VIEW3D_PT_curved_fold_animation(SidebarPanel, bpy.types.Panel):
    bl_label = "Animation & Export"
    bl_parent_id = "VIEW3D_PT_curved_fold_mesh"

    def draw(self, context):
        layout = self.layout
        props = _fold_props(context)
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(props, "solver_mode")
        row = layout.row()
        row.active = props.solver_mode == "DYNAMIC"
        row.prop(props, "steps_per_frame")
        scene = context.scene
        layout.label(text=f"Frames {scene.frame_start}–{scene.frame_end}; baked: {props.baked_frames}")
        stale = bool(context.active_object.get("cf_bake_stale"))
        if stale:
            box = layout.box()
            box.alert = True
            box.label(text="Bake out of date (live re-fold): Re-bake", icon="ERROR")
        elif props.baked_frames and _sources_changed(context):  # a bake folds the stored mesh: Re-fold first
            box = layout.box()
            box.alert = True
            box.label(text="Source curves changed since the bake:", icon="ERROR")
            box.label(text="Re-fold, then Bake again", icon="BLANK1")
        row = layout.row(align=True)
        if stale:
            row.operator("curved_fold.bake", text="Re-bake", icon="RENDER_ANIMATION")
        else:
            row.operator("curved_fold.bake", icon="RENDER_ANIMATION")
        row.operator("curved_fold.clear_bake", text="", icon="X")
        row = layout.row(align=True)
        row.operator("curved_fold.export_folded", text="Export Mesh", icon="EXPORT")
        row.operator("curved_fold.export_pattern_svg", text="Export SVG", icon="FILE_IMAGE")


def _crossing_text(ob) -> str:
    """The panel's self-intersection line: how many faces pass through the sheet elsewhere."""
    count = ob.get("cf_self_intersecting_faces") if ob is not None else None
    if count is None or count < 0:
        return "not measured"
    return f"{count} faces pass through the sheet" if count else "none"


def _glue_text(ob) -> str:
    """The panel's glue line: the largest gap left between glued vertices in the last run."""
    gap = ob.get("cf_glue_gap_mm", -1.0) if ob is not None else -1.0
    return f"{gap:.2e} mm (largest)" if gap >= 0 else "no glue (vertex groups cf_glue_a / cf_glue_b)"


class VIEW3D_PT_curved_fold_figures(SidebarPanel, bpy.types.Panel):
    bl_label = "Last Run"
    bl_parent_id = "VIEW3D_PT_curved_fold_mesh"

    def draw(self, context):
        props = _fold_props(context)
        col = self.layout.column(align=True)
        rows = (
            ("Faces", f"{props.last_faces}  ({props.last_vertices} vertices)"),
            ("Mesh", f"{props.last_generation_ms:.1f} ms"),
            (
                "Solver",
                f"{props.last_ms:.1f} ms ({props.last_cpu_ms:.0f} ms CPU), {props.last_iterations} it."
                + ("" if props.last_converged else " ⚠"),
            ),
            ("Strain", f"{props.last_strain_mean:.4f} % mean, {props.last_strain_max:.4f} % max"),
            ("Warp", f"{props.last_warp_mean:.4f}° mean"),
            ("Fold error", f"{props.last_fold_error:.3f}° mean"),
            ("Crossing", _crossing_text(context.active_object)),
            ("Glue gap", _glue_text(context.active_object)),
        )
        for label, value in rows:
            split = col.split(factor=0.35)
            split.label(text=label)
            split.label(text=value)
        row = self.layout.row(align=True)
        row.operator("curved_fold.show_colours", text="Strain").kind = "STRAIN"
        row.operator("curved_fold.show_colours", text="Warp").kind = "WARP"
        row.operator("curved_fold.show_colours", text="Crossing").kind = "CROSSING"
        row.operator("curved_fold.show_colours", text="", icon="MATERIAL").kind = "NONE"
        row = self.layout.row(align=True)
        row.operator("curved_fold.add_pin_hooks", icon="EMPTY_AXIS")
        row.operator("curved_fold.glue_selected", icon="AUTOMERGE_ON")
        row.operator("curved_fold.clear_glue", text="", icon="X")


CLASSES = (
    VIEW3D_PT_curved_fold_fold,
    VIEW3D_PT_curved_fold_mesh,
    VIEW3D_PT_curved_fold_pattern,
    VIEW3D_PT_curved_fold_solver,
    VIEW3D_PT_curved_fold_animation,
    VIEW3D_PT_curved_fold_figures,
)
