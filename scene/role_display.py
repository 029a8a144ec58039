"""How a crease role shows in the viewport, without destroying the curve's own styling.

A role is shown by colour, as Origami Simulator draws it (border black, mountain red, valley blue, facet yellow,
undriven magenta, cut green): the object colour (Solid mode, Object colour) and a per-role material (Solid mode,
Material colour — the default — and renders). A crease curve with no bevel is drawn only as a thin wire, so a
zero-bevel curve also gets a small round bevel (0.4 % of its size), and 2D filling is turned off, which would
otherwise paint a closed border as a solid black face.

The curve may be the user's own artwork (a logo with its material, object colour and fill), so nothing of it is
lost:

* the role material goes into the **object's** material slots (slot link *Object*), never into the curve data's:
  the data keeps its materials, and linked duplicates sharing the data keep theirs;
* what the role replaces is remembered in ID properties when a role is first set — on the object
  (:data:`OBJECT_STYLE_KEY`: object colour, each slot's link and object-level material) and on the curve data
  (:data:`DATA_STYLE_KEY`: fill mode, bevel, an empty slot added to a curve with none) — and put back exactly when
  the role is set back to None; the data's part only once no other object using that curve data has a role;
* only what still shows the role is put back: a colour, material, fill or bevel the user changed while the role
  was set is theirs and stays.

ID properties are saved in the .blend file and restored by undo, so this survives reloads and Ctrl+Z. A curve
styled by an older version (role material in the data's slot 0, nothing remembered) is cleared as before.
"""

from __future__ import annotations

import bpy

from .properties import ROLE_COLOURS

MATERIAL_PREFIX = "Curved Fold "
"""Per-role materials are named ``"Curved Fold Mountain"`` etc. and shared by every curve of that role."""

OBJECT_STYLE_KEY = "cf_role_style"
"""Object ID property: the object colour and material slots a role replaced (restored when the role is None)."""
DATA_STYLE_KEY = "cf_role_style"
"""Curve ID property: the fill mode and bevel a role replaced and whether it added a material slot."""
AUTO_BEVEL_KEY = "cf_auto_bevel"
"""Curve ID property of older versions: the bevel was added by a role (cleared with the role)."""

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


def _is_role_material(mat: bpy.types.Material | None) -> bool:
    return mat is not None and mat.name.startswith(MATERIAL_PREFIX)


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


def _same_colour(a, b) -> bool:
    return all(abs(x - y) < 1e-6 for x, y in zip(a, b, strict=True))


def show_role(ob: bpy.types.Object) -> None:
    """Show ``ob``'s role (its update callback): colour it for the role, or put its own styling back for ``NONE``.
    Non-curves are left alone."""
    if ob.type != "CURVE":
        return
    if ob.curved_fold.role == "NONE":
        hide_role(ob)
        return
    _remember(ob)
    mat = role_material(ob.curved_fold.role)
    for slot in ob.material_slots:
        slot.link = "OBJECT"
        slot.material = mat
    ob.color = ROLE_COLOURS[ob.curved_fold.role]


def _remember(ob: bpy.types.Object) -> None:
    """Before the first role display: store the object's colour and slots and the curve's fill and bevel, add an
    empty slot to a curve with none, turn 2D fill off and add the bevel. Slots added later are remembered too."""
    style = ob.get(OBJECT_STYLE_KEY)
    if style is None:
        _hide_legacy(ob)  # styled by an older version: start from what clearing its role gave
        ob[OBJECT_STYLE_KEY] = {"color": list(ob.color), "slots": {}}
        style = ob[OBJECT_STYLE_KEY]
    cu = ob.data
    data = cu.get(DATA_STYLE_KEY)
    if data is None:
        cu[DATA_STYLE_KEY] = {}
        data = cu[DATA_STYLE_KEY]
        if len(cu.materials) == 0:  # a slot to hold the object's role material; empty, it draws as none
            cu.materials.append(None)
            data["added_slot"] = True
        if cu.dimensions == "2D" and cu.fill_mode != "NONE":
            data["fill_mode"] = cu.fill_mode
            cu.fill_mode = "NONE"
        if cu.bevel_depth == 0.0 and cu.extrude == 0.0 and cu.bevel_mode == "ROUND" and cu.bevel_object is None:
            data["bevel_resolution"] = cu.bevel_resolution
            cu.bevel_depth = BEVEL_FRACTION * _curve_size(cu)
            cu.bevel_resolution = 2
            data["bevel_depth"] = cu.bevel_depth  # what was set: put back only while it is still this
    slots = style["slots"]
    for i, slot in enumerate(ob.material_slots):
        key = str(i)
        if key in slots or (slot.link == "OBJECT" and _is_role_material(slot.material)):
            continue
        entry = {"link": slot.link}
        if slot.link == "OBJECT" and slot.material is not None:
            entry["material"] = slot.material
        slots[key] = entry


def hide_role(ob: bpy.types.Object) -> None:
    """Role set to None: put back what :func:`show_role` replaced, where it still shows the role."""
    style = ob.get(OBJECT_STYLE_KEY)
    if style is None:
        _hide_legacy(ob)
        return
    slots = style.get("slots", {})
    for i, slot in enumerate(ob.material_slots):
        entry = slots.get(str(i))
        if entry is None or slot.link != "OBJECT" or not _is_role_material(slot.material):
            continue
        slot.material = entry.get("material")
        slot.link = entry.get("link", "DATA")
    if any(_same_colour(ob.color, c) for c in ROLE_COLOURS.values()):
        ob.color = style.get("color", (1.0, 1.0, 1.0, 1.0))
    del ob[OBJECT_STYLE_KEY]
    cu = ob.data
    if cu.users > 1 and any(o is not ob and o.data == cu and o.curved_fold.role != "NONE" for o in bpy.data.objects):
        return  # a linked duplicate still shows a role: the shared curve keeps its role display
    data = cu.get(DATA_STYLE_KEY)
    if data is None:
        return
    if "fill_mode" in data and cu.fill_mode == "NONE":
        cu.fill_mode = data["fill_mode"]
    if "bevel_depth" in data and abs(cu.bevel_depth - data["bevel_depth"]) <= 1e-9 * max(data["bevel_depth"], 1.0):
        cu.bevel_depth = 0.0
        cu.bevel_resolution = data["bevel_resolution"]
    if data.get("added_slot") and len(cu.materials) == 1 and cu.materials[0] is None:
        cu.materials.clear()  # (clear, unlike pop, also takes the slot off the objects)
    del cu[DATA_STYLE_KEY]


def _hide_legacy(ob: bpy.types.Object) -> None:
    """Clear a role display made by an older version (its material in the data's slot 0, the role colour, the
    bevel), as that version did: what it replaced was not kept. A curve without its marks is left alone."""
    cu = ob.data
    in_data = len(cu.materials) > 0 and _is_role_material(cu.materials[0])
    if not in_data and not cu.get(AUTO_BEVEL_KEY):
        return
    if in_data:
        if len(cu.materials) == 1:
            cu.materials.clear()  # (clear, unlike pop, also takes the slot off the objects)
        else:
            cu.materials.pop(index=0)
    if any(_same_colour(ob.color, c) for c in ROLE_COLOURS.values()):
        ob.color = (1.0, 1.0, 1.0, 1.0)
    if cu.get(AUTO_BEVEL_KEY):
        cu.bevel_depth = 0.0
        del cu[AUTO_BEVEL_KEY]
