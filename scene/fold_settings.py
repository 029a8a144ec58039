"""Settings of a folded mesh object (``Object.curved_fold_mesh``): where it came from, how it is folded, last run.

Everything the Re-fold, Live and Bake operators need lives on the folded mesh OBJECT, so a .blend file carries its
own recipe: the source curves (objects or a collection), the pattern parameters (interval, tolerance, mesh type),
the fold angle override and fold percent (keyframable: folding over the timeline is the main animation), the
solver mode and stiffnesses, and the figures of the last run shown in the sidebar.
"""

from __future__ import annotations

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

MESH_TYPES = (
    ("ruling", "Ruling-aware", "Constrained Delaunay triangulation, then edge swaps along estimated rulings (paper)"),
    ("cdt", "Constrained Delaunay", "Constrained Delaunay triangulation without ruling-aware swaps (baseline)"),
    ("earcut", "Ear clipping", "Ear-clipped faces, as Origami Simulator's curved importer does (baseline)"),
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

    is_fold_mesh: BoolProperty(name="Folded Mesh", description="This object was made by Curved Fold", default=False)
    sources: CollectionProperty(type=CURVED_FOLD_PG_source, name="Source Curves")
    source_collection: PointerProperty(
        type=bpy.types.Collection,
        name="Source Collection",
        description="Fold every crease curve in this collection (used instead of the source curve list when set)",
    )
    interval: FloatProperty(
        name="Interval",
        description="Largest chord length of the discretised curves and borders, in mm (0 = automatic from the size)",
        default=0.0,
        min=0.0,
        soft_max=50.0,
        update=_live_update,
    )
    tolerance: FloatProperty(
        name="Tolerance",
        description="Largest distance between a curve and its chords, in mm (0 = automatic from the size)",
        default=0.0,
        min=0.0,
        soft_max=5.0,
        update=_live_update,
    )
    mesh_type: EnumProperty(
        name="Mesh",
        items=MESH_TYPES,
        default="ruling",
        description="How the crease pattern is triangulated",
        update=_live_update,
    )
    use_fold_angle: BoolProperty(
        name="Override Angle",
        description="Give every mountain/valley crease without its own angle this fold angle",
        default=False,
        update=_live_update,
    )
    fold_angle: FloatProperty(
        name="Fold Angle",
        description="Fold angle (degrees, magnitude) for creases that have none; the sign comes from the role",
        default=180.0,
        min=0.0,
        max=180.0,
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
            ("fast", "Fast", "Implicit/Newton-style solver to equilibrium (default)"),
            ("faithful", "Faithful", "Origami Simulator's explicit bar-and-hinge integrator, stepped to rest"),
        ),
        default="fast",
        description="Which solver folds the mesh",
        update=_live_resolve,
    )
    solver_mode: EnumProperty(name="Bake Mode", items=SOLVER_MODES, default="QUASI_STATIC")
    steps_per_frame: IntProperty(
        name="Steps per Frame",
        description="Integrator steps per frame in dynamic mode (Origami Simulator uses 100)",
        default=100,
        min=1,
        soft_max=2000,
    )
    axial_stiffness: FloatProperty(
        name="Axial", description="Bar (stretch) stiffness (Origami Simulator default 20)", default=20.0, min=0.1
    )
    crease_stiffness: FloatProperty(
        name="Crease", description="Mountain/valley hinge stiffness (default 0.7)", default=0.7, min=0.0
    )
    panel_stiffness: FloatProperty(
        name="Panel", description="Facet hinge (bending) stiffness (default 0.7)", default=0.7, min=0.0
    )
    face_stiffness: FloatProperty(
        name="Face", description="Triangle interior-angle stiffness (default 0.2)", default=0.2, min=0.0
    )
    damping: FloatProperty(
        name="Damping", description="Damping ratio of the bars (default 0.45)", default=0.45, min=0.01, max=1.0
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
    # Figures of the last run, shown in the sidebar.
    last_vertices: IntProperty(name="Vertices", default=0)
    last_faces: IntProperty(name="Faces", default=0)
    last_generation_ms: FloatProperty(name="Mesh ms", default=0.0, precision=1)
    last_ms: FloatProperty(name="Solver ms", default=0.0, precision=1)
    last_iterations: IntProperty(name="Iterations", default=0)
    last_converged: BoolProperty(name="Converged", default=False)
    last_strain_mean: FloatProperty(name="Mean Strain %", default=0.0, precision=4)
    last_strain_max: FloatProperty(name="Max Strain %", default=0.0, precision=4)
    last_warp_mean: FloatProperty(name="Mean Warp °", default=0.0, precision=4)
    last_fold_error: FloatProperty(name="Fold-angle Error °", default=0.0, precision=3)
    last_message: StringProperty(name="Message", default="")
    baked_frames: IntProperty(name="Baked Frames", default=0)


CLASSES = (CURVED_FOLD_PG_source, CURVED_FOLD_PG_mesh)


def register_extra() -> None:
    bpy.types.Object.curved_fold_mesh = PointerProperty(type=CURVED_FOLD_PG_mesh)


def unregister_extra() -> None:
    if hasattr(bpy.types.Object, "curved_fold_mesh"):
        del bpy.types.Object.curved_fold_mesh


def settings_dict(props: CURVED_FOLD_PG_mesh) -> dict:
    """The solver-relevant values of ``props`` as a plain dict (what ``core`` receives; no bpy objects)."""
    return {
        "axial_stiffness": float(props.axial_stiffness),
        "crease_stiffness": float(props.crease_stiffness),
        "panel_stiffness": float(props.panel_stiffness),
        "face_stiffness": float(props.face_stiffness),
        "damping": float(props.damping),
        "isometric": bool(props.isometric),
    }
