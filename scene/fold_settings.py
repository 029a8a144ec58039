"""Settings of a folded mesh object (``Object.curved_fold_mesh``): where it came from, how it is folded, last run.

Everything the Re-fold, Live and Bake operators need lives on the folded mesh OBJECT, so a .blend file carries its
own recipe: the source curves (objects or a collection), the pattern parameters (interval, tolerance, mesh type),
the fold angle override and fold percent (keyframable: folding over the timeline is the main animation), the
solver mode and stiffnesses, and the figures of the last run shown in the sidebar.

With Live on, every setting that changes the fold schedules a re-fold: the pattern settings (interval, tolerance,
mesh, override angle, source collection) a rebuild, the solve settings (fold percent, solver, isometric,
stiffnesses, damping) a warm-started re-solve. The bake settings (bake mode, steps per frame) only matter to Bake.
"""

from __future__ import annotations

import math
from dataclasses import replace

import bpy
import numpy as np
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from .single_precision import as_typed


def engine_id(identifier: str) -> str:
    """The engine's name (``core.mesh.build``'s mesh types, ``core.solve.solver``'s methods) of a Blender enum
    identifier: Blender's enum identifiers are upper case (``RULING``, ``FAST``), the engine's and the command line's
    names lower case (``ruling``, ``fast``)."""
    return identifier.lower()


MESH_TYPES = (
    ("RULING", "Ruling-aware", "Constrained Delaunay triangulation, then edge swaps along estimated rulings (paper)"),
    ("CDT", "Constrained Delaunay", "Constrained Delaunay triangulation without ruling-aware swaps (baseline)"),
    ("EARCUT", "Ear clipping", "Ear-clipped faces, as Origami Simulator's curved importer does (baseline)"),
)

SOLVER_MODES = (
    ("QUASI_STATIC", "Quasi-static", "Solve each frame to equilibrium (fast solver, warm-started from the last frame)"),
    ("DYNAMIC", "Dynamic", "Step the bar-and-hinge integrator a fixed number of steps per frame (velocities carried)"),
)


def _schedule(self, rebuild: bool) -> None:
    if not getattr(self, "live", False):
        return
    from . import live  # lazy: live imports folding, which imports these settings

    owner = self.id_data
    if isinstance(owner, bpy.types.Object):
        live.schedule_refold(owner.name, rebuild=rebuild)


def _live_update(self, context) -> None:
    """Update callback of pattern settings: when Live is on, schedule a debounced re-fold with a rebuilt mesh."""
    _schedule(self, True)


def _live_resolve(self, context) -> None:
    """Update callback of solve-only settings (fold percent, solver): when Live is on, schedule a debounced
    re-solve of the stored mesh, warm-started from the current shape (cheap: no re-meshing)."""
    _schedule(self, False)


class CURVED_FOLD_PG_source(bpy.types.PropertyGroup):
    """One source curve object of a folded mesh."""

    object: PointerProperty(type=bpy.types.Object, name="Curve", description="A crease curve this mesh was built from")


class CURVED_FOLD_PG_mesh(bpy.types.PropertyGroup):
    """Recipe and last-run figures of a folded mesh object (``Object.curved_fold_mesh``)."""

    is_fold_mesh: BoolProperty(
        name="Folded Mesh", description="This object was made by Curved Fold (read-only)", default=False, options=set()
    )
    sources: CollectionProperty(
        type=CURVED_FOLD_PG_source,
        name="Source Curves",
        description="The crease curves this mesh was folded from (Re-fold and Live rebuild from them)",
    )
    source_collection: PointerProperty(
        type=bpy.types.Collection,
        name="Source Collection",
        description="Fold every crease curve in this collection (used instead of the source curve list when set)",
        update=_live_update,
    )
    interval: FloatProperty(
        name="Interval",
        description="Largest chord length of the discretised curves and borders, and of the pieces of a straight "
        "crease split beside needle triangles (0 = automatic: the paper's 7 mm per 150 mm of sheet)",
        default=0.0,
        min=0.0,  # no soft_max: in Blender units it meant 50 mm at Unit Scale 1 but 0.05 mm at 0.001
        precision=4,
        subtype="DISTANCE",
        unit="LENGTH",
        update=_live_update,
    )
    tolerance: FloatProperty(
        name="Tolerance",
        description="Largest distance between a curve and its chords (0 = automatic: the paper's 0.07 mm per 150 mm "
        "of sheet)",
        default=0.0,
        min=0.0,
        precision=5,
        subtype="DISTANCE",
        unit="LENGTH",
        update=_live_update,
    )
    mesh_type: EnumProperty(
        name="Mesh",
        items=MESH_TYPES,
        default="RULING",
        description="How the crease pattern is triangulated",
        update=_live_update,
    )
    use_fold_angle: BoolProperty(
        name="Override Crease Angles",
        description="Fold every mountain and valley crease of this mesh to the angle below, whatever angle its "
        "curve has (the curves are not changed)",
        default=False,
        options=set(),
        update=_live_update,
    )
    fold_angle: FloatProperty(
        name="Fold Angle",
        description="Fold angle of every mountain and valley crease when Override Crease Angles is on (0° flat, "
        "180° folded flat); the sign comes from the role. Not animatable: it is part of the pattern (animate Fold "
        "Percent instead)",
        default=math.pi,
        min=0.0,
        max=math.pi,
        subtype="ANGLE",
        unit="ROTATION",
        options=set(),  # keys on it did nothing (playback and bake fold the stored pattern's angles)
        update=_live_update,
    )
    fold_percent: FloatProperty(
        name="Fold Percent",
        description="How far the creases fold toward their target angles (keyframe it to animate the fold)",
        default=100.0,
        min=0.0,
        max=100.0,
        subtype="PERCENTAGE",
        update=_live_resolve,
    )
    solver: EnumProperty(
        name="Solver",
        items=(
            ("FAST", "Fast", "Implicit/Newton-style solver to equilibrium (default)"),
            ("FAITHFUL", "Faithful", "Origami Simulator's explicit bar-and-hinge integrator, stepped to rest"),
        ),
        default="FAST",
        description="Which solver folds the mesh",
        update=_live_resolve,
    )
    solver_mode: EnumProperty(
        name="Bake Mode",
        description="How Bake steps the fold from frame to frame",
        items=SOLVER_MODES,
        default="QUASI_STATIC",
    )
    steps_per_frame: IntProperty(
        name="Steps per Frame",
        description="Integrator steps per frame in dynamic mode (Origami Simulator uses 100)",
        default=100,
        min=1,
        soft_max=2000,
    )
    axial_stiffness: FloatProperty(
        name="Axial",
        description="Bar (stretch) stiffness (Origami Simulator default 20)",
        default=20.0,
        min=0.1,
        update=_live_resolve,
    )
    crease_stiffness: FloatProperty(
        name="Crease",
        description="Mountain/valley hinge stiffness (default 0.7)",
        default=0.7,
        min=0.0,
        update=_live_resolve,
    )
    panel_stiffness: FloatProperty(
        name="Panel",
        description="Facet hinge (bending) stiffness (default 0.7)",
        default=0.7,
        min=0.0,
        update=_live_resolve,
    )
    face_stiffness: FloatProperty(
        name="Face",
        description="Triangle interior-angle stiffness (default 0.2)",
        default=0.2,
        min=0.0,
        update=_live_resolve,
    )
    damping: FloatProperty(
        name="Damping",
        description="Damping ratio of the bars (default 0.45; the dynamic solver and bake)",
        default=0.45,
        min=0.01,
        max=1.0,
        update=_live_resolve,
    )
    isometric: BoolProperty(
        name="Isometric",
        description="Much stiffer bars so the paper barely stretches (strain well under 0.1 %)",
        default=False,
        update=_live_resolve,
    )
    live: BoolProperty(
        name="Live",
        description="Re-fold automatically while the source crease curves or these settings are edited",
        default=False,
        update=_live_update,
    )
    # Figures of the last run, shown in the sidebar as labels. Results, not settings: not animatable (options=set()
    # drops ANIMATABLE), written only by the add-on.
    last_vertices: IntProperty(name="Vertices", description="Vertices of the folded mesh (last run)", options=set())
    last_faces: IntProperty(name="Faces", description="Triangles of the folded mesh (last run)", options=set())
    last_generation_ms: FloatProperty(
        name="Mesh ms", description="Time spent triangulating (last run)", precision=1, options=set()
    )
    last_ms: FloatProperty(name="Solver ms", description="Time spent solving (last run)", precision=1, options=set())
    last_cpu_ms: FloatProperty(
        name="Solver CPU ms", description="CPU time spent solving (last run)", precision=1, options=set()
    )
    last_iterations: IntProperty(name="Iterations", description="Solver iterations (last run)", options=set())
    last_converged: BoolProperty(
        name="Converged", description="The solver reached equilibrium (last run)", options=set()
    )
    last_strain_mean: FloatProperty(
        name="Mean Strain %", description="Mean bar strain in percent (last run)", precision=4, options=set()
    )
    last_strain_max: FloatProperty(
        name="Max Strain %", description="Largest bar strain in percent (last run)", precision=4, options=set()
    )
    last_warp_mean: FloatProperty(
        name="Mean Warp °",
        description="Mean warp angle of the triangles in degrees: how far the rulings are from the mesh (last run)",
        precision=4,
        options=set(),
    )
    last_fold_error: FloatProperty(
        name="Fold-angle Error °",
        description="Mean |simulated − target| crease angle in degrees (last run)",
        precision=3,
        options=set(),
    )
    last_message: StringProperty(
        name="Message", description='The "does not fold as assigned" message of the last run', options=set()
    )
    baked_frames: IntProperty(name="Baked Frames", description="Frames baked to shape keys", options=set())


CLASSES = (CURVED_FOLD_PG_source, CURVED_FOLD_PG_mesh)


def register_extra() -> None:
    bpy.types.Object.curved_fold_mesh = PointerProperty(type=CURVED_FOLD_PG_mesh)


def unregister_extra() -> None:
    if hasattr(bpy.types.Object, "curved_fold_mesh"):
        del bpy.types.Object.curved_fold_mesh


def pattern_parameters(owner, scene: bpy.types.Scene | None = None) -> dict[str, float]:
    """``interval`` and ``tolerance`` of a fold object's settings (or the Fold operator) in millimetres, as the
    engine takes them; the properties are lengths in Blender units (shown in the scene's unit). 0 = automatic."""
    from .mesh_object import mm_per_unit

    mm = mm_per_unit(scene)
    return {"interval": float(owner.interval) * mm, "tolerance": float(owner.tolerance) * mm}


def override_angle_degrees(owner) -> float | None:
    """The Override Crease Angles angle of a fold object's settings (or the Fold operator) in degrees, the engine's
    unit (the property is an angle in radians, shown in the scene's rotation unit); ``None`` when it is off."""
    if owner is None or not owner.use_fold_angle:
        return None
    return math.degrees(float(owner.fold_angle))


def override_fold_angles(pattern, angle: float | None):
    """``pattern`` with every mountain and valley crease at ``angle`` degrees (valley +, mountain −): the folded
    mesh's Override Crease Angles, which applies to every crease, whatever angle its curve carries.

    ``None`` leaves the pattern unchanged."""
    if angle is None:
        return pattern
    angles = np.array(pattern.fold_angles, dtype=np.float64)
    assign = np.asarray(pattern.assignments)
    angles[assign == "V"] = abs(float(angle))
    angles[assign == "M"] = -abs(float(angle))
    return replace(pattern, fold_angles=angles)


def settings_dict(props: CURVED_FOLD_PG_mesh) -> dict:
    """The solver-relevant values of ``props`` as a plain dict (what ``core`` receives; no bpy objects), each float
    :func:`as_typed`."""
    return {
        "axial_stiffness": as_typed(props.axial_stiffness),
        "crease_stiffness": as_typed(props.crease_stiffness),
        "panel_stiffness": as_typed(props.panel_stiffness),
        "face_stiffness": as_typed(props.face_stiffness),
        "damping": as_typed(props.damping),
        "isometric": bool(props.isometric),
    }
