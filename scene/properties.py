"""Crease role and fold angle of a curve object (``Object.curved_fold``), and how a role shows in the viewport.

A designer draws creases as Bézier curve objects and gives each one a *role* — border, mountain, valley, facet,
undriven or cut (FOLD's assignments B M V F U C) — and, for mountains and valleys, a fold angle. The magnitude is
stored (0–180°; as every Blender angle property, in radians, shown in the scene's rotation unit); the sign comes from
the role, FOLD's convention: valley positive, mountain negative. The default, 180°, is what an Origami Simulator SVG
line at full opacity means. :attr:`CurvedFoldObjectProperties.signed_fold_angle` gives degrees, the engine's unit.

A role is shown by colour, as Origami Simulator draws it (border black, mountain red, valley blue, facet yellow,
undriven magenta, cut green): the object colour (Solid mode, Object colour) and a per-role material
(Solid mode, Material colour — the default — and renders). A crease curve with no bevel is drawn only as a thin
wire, in the theme colour, so setting a role also gives a zero-bevel curve a small round bevel (0.4 % of its size)
and turns off 2D filling, which would otherwise paint closed borders as solid black faces.
"""

import math

import bpy

ROLE_ASSIGNMENT = {
    "BORDER": "B",
    "MOUNTAIN": "M",
    "VALLEY": "V",
    "FACET": "F",
    "UNDRIVEN": "U",
    "CUT": "C",
}
"""Role enum identifier → FOLD assignment letter (``NONE`` has none: the curve is not a crease)."""

ASSIGNMENT_ROLE = {v: k for k, v in ROLE_ASSIGNMENT.items()}

ROLE_COLOURS: dict[str, tuple[float, float, float, float]] = {
    "BORDER": (0.0, 0.0, 0.0, 1.0),
    "MOUNTAIN": (1.0, 0.0, 0.0, 1.0),
    "VALLEY": (0.0, 0.0, 1.0, 1.0),
    "FACET": (1.0, 1.0, 0.0, 1.0),
    "UNDRIVEN": (1.0, 0.0, 1.0, 1.0),
    "CUT": (0.0, 1.0, 0.0, 1.0),
}
"""Origami Simulator's colours per role (linear RGBA)."""

ROLE_ITEMS = [
    ("NONE", "None", "Not a crease: ignored when folding", "BLANK1", 0),
    ("BORDER", "Border", "Edge of the sheet (black)", "SELECT_SET", 1),
    ("MOUNTAIN", "Mountain", "Mountain fold: folds away from the viewer, negative fold angle (red)", "TRIA_UP", 2),
    ("VALLEY", "Valley", "Valley fold: folds towards +Z, positive fold angle (blue)", "TRIA_DOWN", 3),
    ("FACET", "Facet", "Flat crease, target fold angle 0 (yellow)", "REMOVE", 4),
    ("UNDRIVEN", "Undriven", "Free hinge with no target angle (magenta)", "UNLINKED", 5),
    ("CUT", "Cut", "Cut through the sheet (green)", "SCULPTMODE_HLT", 6),
]

MATERIAL_PREFIX = "Curved Fold "
"""Per-role materials are named ``"Curved Fold Mountain"`` etc. and shared by every curve of that role."""

AUTO_BEVEL_KEY = "cf_auto_bevel"
"""Custom property on a curve whose bevel was added by :func:`show_role` (removed again when the role is cleared)."""

BEVEL_FRACTION = 0.004
"""Bevel given to a zero-bevel crease curve when a role is set, as a fraction of the curve's largest dimension."""


def role_material(role: str) -> bpy.types.Material:
    """The shared material for ``role`` (created on first use), coloured as Origami Simulator draws it."""
    name = MATERIAL_PREFIX + role.title()
    mat = bpy.data.materials.get(name)
    if mat is None:
        mat = bpy.data.materials.new(name)
    colour = ROLE_COLOURS[role]
    mat.diffuse_color = colour
    if mat.node_tree is not None:  # materials made in the UI use nodes; keep their base colour in step
        bsdf = mat.node_tree.nodes.get("Principled BSDF")
        if bsdf is not None:
            bsdf.inputs["Base Color"].default_value = colour
    return mat


def _curve_size(cu: bpy.types.Curve) -> float:
    """Largest extent of the curve's control points (local units); 1.0 for an empty curve."""
    points = []
    for spline in cu.splines:
        points.extend(bp.co for bp in spline.bezier_points)
        points.extend(p.co for p in spline.points)
    if not points:
        return 1.0
    extent = max(max(p[i] for p in points) - min(p[i] for p in points) for i in range(3))
    return extent if extent > 0.0 else 1.0


def show_role(ob: bpy.types.Object) -> None:
    """Colour ``ob`` for its role and make its curve visible in Solid mode (no-op for ``NONE`` or non-curves)."""
    role = ob.curved_fold.role
    if ob.type != "CURVE":
        return
    if role == "NONE":
        _hide_role(ob)
        return
    ob.color = ROLE_COLOURS[role]
    cu = ob.data
    mat = role_material(role)
    if len(cu.materials) == 0:
        cu.materials.append(mat)
    else:
        cu.materials[0] = mat
    for spline in cu.splines:
        spline.material_index = 0
    if cu.bevel_depth == 0.0 and cu.extrude == 0.0 and cu.bevel_mode == "ROUND" and cu.bevel_object is None:
        cu.bevel_depth = BEVEL_FRACTION * _curve_size(cu)
        cu.bevel_resolution = 2
        cu[AUTO_BEVEL_KEY] = True
    if cu.dimensions == "2D":
        cu.fill_mode = "NONE"


def _hide_role(ob: bpy.types.Object) -> None:
    """Undo what :func:`show_role` added (role cleared): our material, the object colour, an automatic bevel."""
    cu = ob.data
    if len(cu.materials) and cu.materials[0] is not None and cu.materials[0].name.startswith(MATERIAL_PREFIX):
        cu.materials.pop(index=0)
    ob.color = (1.0, 1.0, 1.0, 1.0)
    if cu.get(AUTO_BEVEL_KEY):
        cu.bevel_depth = 0.0
        del cu[AUTO_BEVEL_KEY]


def _update_role(self: "CurvedFoldObjectProperties", context: bpy.types.Context) -> None:
    ob = self.id_data
    if isinstance(ob, bpy.types.Object):
        show_role(ob)


def _update_angle(self: "CurvedFoldObjectProperties", context: bpy.types.Context) -> None:
    """Tag the object as updated: a Python property changes no Blender data by itself, so without this the
    depsgraph handlers (Live re-fold, the out-of-date notice of :mod:`.source_state`) would not see a new angle."""
    ob = self.id_data
    if isinstance(ob, bpy.types.Object):
        ob.update_tag()


class CurvedFoldObjectProperties(bpy.types.PropertyGroup):
    """Crease settings of one curve object (``Object.curved_fold``)."""

    role: bpy.props.EnumProperty(
        name="Crease Role",
        description="What this curve is in the crease pattern (Origami Simulator colors: border black, mountain "
        "red, valley blue, facet yellow, undriven magenta, cut green)",
        items=ROLE_ITEMS,
        default="NONE",
        update=_update_role,
    )
    fold_angle: bpy.props.FloatProperty(
        name="Fold Angle",
        description="Target fold angle of a mountain or valley crease (0° = flat, 180° = folded flat); the sign "
        "comes from the role: valleys fold towards +Z, mountains away",
        default=math.pi,
        min=0.0,
        max=math.pi,
        precision=1,
        subtype="ANGLE",
        unit="ROTATION",
        update=_update_angle,
    )

    @property
    def assignment(self) -> str | None:
        """FOLD assignment letter of the role, ``None`` for ``NONE``."""
        return ROLE_ASSIGNMENT.get(self.role)

    @property
    def signed_fold_angle(self) -> float | None:
        """Fold angle in degrees with FOLD's sign (valley +, mountain −), 0 for facets, ``None`` where the role has
        none."""
        if self.role == "VALLEY":
            return round(math.degrees(self.fold_angle), 4)
        if self.role == "MOUNTAIN":
            return -round(math.degrees(self.fold_angle), 4)
        if self.role == "FACET":
            return 0.0
        return None


CLASSES = (CurvedFoldObjectProperties,)


def register_extra() -> None:
    bpy.types.Object.curved_fold = bpy.props.PointerProperty(
        type=CurvedFoldObjectProperties,
        name="Curved Fold",
        description="Crease role and fold angle of this curve (Curved Fold)",
    )


def unregister_extra() -> None:
    if hasattr(bpy.types.Object, "curved_fold"):
        del bpy.types.Object.curved_fold
