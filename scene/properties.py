"""Crease role and fold angle of a curve object (``Object.curved_fold``), and how a role shows in the viewport.

A designer draws creases as Bézier curve objects and gives each one a *role* — border, mountain, valley, facet,
undriven or cut (FOLD's assignments B M V F U C) — and, for mountains and valleys, a fold angle. The magnitude is
stored (0–180°; as every Blender angle property, in radians, shown in the scene's rotation unit); the sign comes from
the role, FOLD's convention: valley positive, mountain negative. The default, 180°, is what an Origami Simulator SVG
line at full opacity means. :attr:`CurvedFoldObjectProperties.signed_fold_angle` gives degrees, the engine's unit.

A role is shown by colour, as Origami Simulator draws it, by :mod:`.role_display` (the role's update callback),
which keeps the curve's own materials, object colour, fill and bevel and puts them back when the role is None.
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


def _update_role(self: "CurvedFoldObjectProperties", context: bpy.types.Context) -> None:
    """Show the new role in the viewport (or the curve's own styling again for None)."""
    ob = self.id_data
    if isinstance(ob, bpy.types.Object):
        from .role_display import show_role  # lazy: role_display reads this module's colours

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
