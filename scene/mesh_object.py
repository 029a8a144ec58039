"""Write a folded :class:`~..core.mesh.FoldMesh` into Blender as a mesh object, and read it back.

The object carries the whole flat pattern as attributes, so re-folding and baking never rebuild it:

* ``cf_flat`` (FLOAT2, point): flat position in mm, in the sheet's plane
* ``cf_assignment`` (INT8, edge): index into :data:`~..core.pattern.ASSIGNMENTS` (B M V F U C)
* ``cf_fold_angle`` (FLOAT, edge): target fold angle in degrees (valley > 0), ``nan`` for no target
* ``cf_fold_angle_sim`` (FLOAT, edge): simulated fold angle of the last run
* ``cf_from_curve`` (BOOLEAN, edge), ``cf_polyline`` (INT, edge): which edges discretise a drawn curve/stroke
* ``cf_face`` (INT, face): crease-pattern face each triangle belongs to
* ``cf_strain`` / ``cf_warp`` (FLOAT_COLOR, point / corner): Origami Simulator's strain colours and warp angle
  colours (flat per triangle), for the viewport's Attribute colour mode; ``cf_strain_pct`` (point) and
  ``cf_warp_deg`` (face) hold the raw values.

Blender's attributes are single precision, so the flat positions and the target fold angles are also kept exactly,
as double-precision ID properties (:data:`EXACT_FLAT_KEY`, :data:`EXACT_ANGLE_KEY`), used while they round to the
attributes: an Export SVG, a Re-fold or a bake then starts from the pattern the fold was made of, to the last bit,
not from a copy moved by up to 4e-6 mm (a ten-ring pleat written from it took 142 iterations instead of 132).

Crease edges are shown as two child curve objects (``<name> Mountain`` in red, ``<name> Valley`` in blue, a small
bevel so they render in Solid, Workbench and Cycles alike); they follow every re-fold and every baked frame.

Positions are millimetres in :mod:`..core`; Blender units are ``mm / (1000 · scale_length)``, the inverse of
``scene.curves.curves_from_objects``.
"""

from __future__ import annotations

import colorsys

import bpy
import numpy as np

from ..core.mesh.fold_mesh import FoldMesh
from ..core.pattern.model import ASSIGNMENTS
from ..core.pattern.polylines import chain_edges
from .single_precision import as_typed

CREASE_COLOURS = {"M": (1.0, 0.0, 0.0, 1.0), "V": (0.0, 0.1, 1.0, 1.0)}
"""Viewport colours of crease edges, as Origami Simulator draws them (mountain red, valley blue)."""

STRAIN_CLIP_PCT = 5.0
"""Strain (percent) at which the strain colour saturates to red (Origami Simulator's ``strainClip``)."""

WARP_CLIP_DEG = 10.0
"""Warp angle (degrees) at which the warp colour saturates to red."""

_EDGE_ATTRS = ("cf_assignment", "cf_fold_angle", "cf_fold_angle_sim", "cf_from_curve", "cf_polyline")


def mm_per_unit(scene: bpy.types.Scene | None = None) -> float:
    """Millimetres per Blender unit in ``scene`` (1 BU = 1000 mm × ``unit_settings.scale_length``)."""
    scene = scene or bpy.context.scene
    scale = as_typed(scene.unit_settings.scale_length) if scene is not None else 1.0
    return 1000.0 * (scale if scale > 0 else 1.0)


EXACT_FLAT_KEY, EXACT_ANGLE_KEY = "cf_flat_exact", "cf_fold_angle_exact"
"""ID properties of a fold mesh: ``cf_flat`` (x, y per vertex) and ``cf_fold_angle`` (per edge, Blender's order) as
doubles, exactly as the fold had them."""

FLAT_UNIT_KEY = "cf_mm_per_unit"
"""ID property of a fold mesh: :func:`mm_per_unit` of the scene when its flat pattern (``cf_flat``, mm) was written."""


def flat_rescale(me: bpy.types.Mesh, scene: bpy.types.Scene | None = None) -> float:
    """Factor that turns the stored flat pattern's millimetres into the scene's millimetres now.

    Changing the scene's Unit Scale changes what a Blender unit means, not the geometry: the curves and the folded
    mesh keep their size in Blender units. The flat pattern was stored in the millimetres of the fold's unit scale,
    so it is read back × (mm per unit now / then); without this, a re-solve or bake after switching Unit Scale from
    1 to 0.001 wrote the sheet 1000× larger than its curves. Meshes stored before the key existed: 1."""
    then = me.get(FLAT_UNIT_KEY)
    return 1.0 if not then else mm_per_unit(scene) / float(then)


def _edge_keys(edges: np.ndarray, n: int) -> np.ndarray:
    e = np.sort(np.asarray(edges, dtype=np.int64).reshape(-1, 2), axis=1)
    return e[:, 0] * n + e[:, 1]


def blender_edge_order(me: bpy.types.Mesh, mesh: FoldMesh) -> np.ndarray:
    """For each Blender edge of ``me``, the index of the same edge in ``mesh.edges`` (vectorised key lookup).

    Blender builds its own edge list from the faces, so the order differs from the FoldMesh's; every attribute
    write goes through this permutation. Raises ``ValueError`` naming the first edge that has no partner.
    """
    n = len(me.vertices)
    be = np.empty(len(me.edges) * 2, dtype=np.int32)
    me.edges.foreach_get("vertices", be)
    bkeys = _edge_keys(be, n)
    fkeys = _edge_keys(mesh.edges, n)
    order = np.argsort(fkeys)
    pos = np.searchsorted(fkeys[order], bkeys)
    pos = np.clip(pos, 0, len(order) - 1)
    found = order[pos]
    bad = fkeys[found] != bkeys
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(f"mesh '{me.name}': Blender edge {i} {be[2 * i : 2 * i + 2].tolist()} is not in the fold mesh")
    return found


def _set_attr(me: bpy.types.Mesh, name: str, type_: str, domain: str, values: np.ndarray, key: str) -> None:
    attr = me.attributes.get(name)
    if attr is not None and (attr.data_type != type_ or attr.domain != domain):
        me.attributes.remove(attr)
        attr = None
    if attr is None:
        attr = me.attributes.new(name=name, type=type_, domain=domain)
    attr.data.foreach_set(key, np.ascontiguousarray(values).ravel())


def _get_attr(me: bpy.types.Mesh, name: str, key: str, dtype, count: int, width: int = 1) -> np.ndarray:
    attr = me.attributes.get(name)
    if attr is None:
        raise ValueError(f"mesh '{me.name}' has no '{name}' attribute: it was not made by Curved Fold's Fold operator")
    out = np.empty(count * width, dtype=dtype)
    attr.data.foreach_get(key, out)
    return out.reshape(-1, width) if width > 1 else out


def _exact(me: bpy.types.Mesh, key: str, stored: np.ndarray) -> np.ndarray:
    """The double-precision copy of the float32 attribute values ``stored`` kept under ``key``, when it still rounds
    to them (not after the mesh was edited, its elements sorted, or by an older version: then ``stored``)."""
    exact = me.get(key)
    if exact is not None and len(exact) == stored.size:
        values = np.array(exact.to_list() if hasattr(exact, "to_list") else exact, dtype=np.float64)
        if np.array_equal(values.astype(np.float32), stored.ravel(), equal_nan=True):
            return values.reshape(stored.shape)
    return stored.astype(np.float64)


def simulated_fold_angles(ob: bpy.types.Object) -> np.ndarray | None:
    """The last run's simulated fold angles per edge (``cf_fold_angle_sim``, degrees, unwrapped as the solver keeps
    them: a valley past flat is 199°), in :func:`read_fold_mesh`'s edge order; ``None`` if the mesh has none."""
    me = ob.data
    if me.attributes.get("cf_fold_angle_sim") is None:
        return None
    values = _get_attr(me, "cf_fold_angle_sim", "value", np.float32, len(me.edges)).astype(np.float64)
    return values[_sorted_edges(me)[1]]


def _sorted_edges(me: bpy.types.Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Blender's edges as sorted vertex pairs in the order a built :class:`FoldMesh` has them (by first vertex, then
    second), and the permutation from Blender's order. Read back in Blender's own order, a Re-fold summed the hinges
    in another order than the Fold: on a pattern that stops at the round-off floor 159 iterations became 176, and a
    vertex moved 3 mm."""
    pairs = np.empty(2 * len(me.edges), dtype=np.int64)
    me.edges.foreach_get("vertices", pairs)
    pairs = np.sort(pairs.reshape(-1, 2), axis=1)
    order = np.lexsort((pairs[:, 1], pairs[:, 0]))
    return pairs[order], order


def assignment_codes(assignments: np.ndarray) -> np.ndarray:
    """FOLD letters → their index in :data:`ASSIGNMENTS` (the ``cf_assignment`` code), vectorised."""
    letters = np.asarray(assignments, dtype="<U1")
    codes = np.full(len(letters), -1, dtype=np.int32)
    for i, a in enumerate(ASSIGNMENTS):
        codes[letters == a] = i
    if (codes < 0).any():
        bad = int(np.flatnonzero(codes < 0)[0])
        raise ValueError(f"edge {bad} has unknown assignment {str(letters[bad])!r}; expected one of {ASSIGNMENTS}")
    return codes


def _srgb_to_linear(c: np.ndarray) -> np.ndarray:
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def heat_colours(values: np.ndarray, clip: float) -> np.ndarray:
    """Origami Simulator's strain colour map: hue 0.7·(1 − min(v, clip)/clip), s 1, l 0.5; blue 0 → red ≥ clip.

    Returns linear RGBA float32 ``(k, 4)`` (Blender's FLOAT_COLOR attributes are scene-linear). Non-finite values
    are grey.
    """
    v = np.asarray(values, dtype=np.float64).reshape(-1)
    finite = np.isfinite(v)
    t = np.clip(np.where(finite, v, 0.0) / clip, 0.0, 1.0)
    # colorsys is scalar; the palette is quantised to 256 steps and looked up vectorised.
    lut = np.array([colorsys.hls_to_rgb(0.7 * (1.0 - k / 255.0), 0.5, 1.0) for k in range(256)])
    rgb = lut[np.rint(t * 255).astype(int)]
    rgb[~finite] = 0.5
    out = np.ones((len(v), 4), dtype=np.float32)
    out[:, :3] = _srgb_to_linear(rgb)
    return out


def _material(name: str, colour: tuple[float, float, float, float]) -> bpy.types.Material:
    mat = bpy.data.materials.get(name)
    if mat is None:
        mat = bpy.data.materials.new(name)
        mat.diffuse_color = colour  # Solid/Workbench
        try:
            if mat.node_tree is None:  # Blender < 5.0 (5.0 deprecates use_nodes: materials always have nodes)
                mat.use_nodes = True
            bsdf = mat.node_tree.nodes.get("Principled BSDF")
            if bsdf is not None:
                bsdf.inputs["Base Color"].default_value = colour
        except (AttributeError, KeyError, TypeError):  # pragma: no cover - node API differences
            pass
    return mat


def crease_polylines(mesh: FoldMesh, assignment: str) -> list[np.ndarray]:
    """Chains of vertex indices along the crease edges of one assignment (``"M"`` or ``"V"``)."""
    return chain_edges(mesh.edges[mesh.assignments == assignment])


def _crease_curve_objects(ob: bpy.types.Object) -> dict[str, bpy.types.Object]:
    return {
        child["cf_crease_role"]: child
        for child in ob.children
        if child.type == "CURVE" and child.get("cf_crease_role") in CREASE_COLOURS
    }


def _write_crease_curves(ob: bpy.types.Object, mesh: FoldMesh, positions_bu: np.ndarray) -> list[bpy.types.Object]:
    """Create (or rebuild) the red/blue crease-curve children of ``ob`` at ``positions_bu`` (local coordinates)."""
    made = []
    existing = _crease_curve_objects(ob)
    size = max(float(np.ptp(positions_bu[:, 0])), float(np.ptp(positions_bu[:, 1])), 1e-9)
    for role, label in (("M", "Mountain"), ("V", "Valley")):
        chains = crease_polylines(mesh, role)
        child = existing.get(role)
        if not chains:
            if child is not None:
                data = child.data
                bpy.data.objects.remove(child)
                if data.users == 0:
                    bpy.data.curves.remove(data)
            continue
        if child is None:
            cu = bpy.data.curves.new(f"{ob.name} {label}", type="CURVE")
            cu.dimensions = "3D"
            child = bpy.data.objects.new(f"{ob.name} {label}", cu)
            child["cf_crease_role"] = role
            for coll in ob.users_collection:
                coll.objects.link(child)
            child.parent = ob
            child.hide_select = True
            cu.materials.append(_material(f"Curved Fold Crease {label}", CREASE_COLOURS[role]))
            child.color = CREASE_COLOURS[role]
        cu = child.data
        if cu.shape_keys is not None:
            child.shape_key_clear()
        cu.splines.clear()
        cu.bevel_depth = 0.0025 * size
        cu.bevel_resolution = 1
        for chain in chains:
            sp = cu.splines.new("POLY")
            sp.points.add(len(chain) - 1)
            co = np.ones((len(chain), 4), dtype=np.float32)
            co[:, :3] = child_points(child, positions_bu[chain])
            sp.points.foreach_set("co", co.ravel())
        child["cf_chains"] = np.concatenate(chains).astype(np.int32).tolist()
        made.append(child)
    return made


def crease_point_indices(child: bpy.types.Object) -> np.ndarray:
    """Fold-mesh vertex index of every point of a crease-curve child, in spline order."""
    return np.asarray(child.get("cf_chains", []), dtype=np.int64)


def create_fold_object(
    mesh: FoldMesh,
    positions: np.ndarray,
    name: str,
    collection: bpy.types.Collection,
    *,
    fold_angles_sim: np.ndarray | None = None,
    strain_pct: np.ndarray | None = None,
    warp_deg: np.ndarray | None = None,
    scene: bpy.types.Scene | None = None,
    creases: bool = True,
) -> bpy.types.Object:
    """Make a new mesh object from ``mesh`` at ``positions`` (``(n, 3)`` mm) in ``collection``; return it.

    All ``cf_`` attributes are written (see the module docstring). On any failure nothing is left behind: the
    half-made object, its mesh and crease curves are removed before the exception propagates. ``creases=False``
    skips the red/blue crease-curve children (exports).
    """
    positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    if len(positions) != mesh.n_vertices:
        raise ValueError(f"positions have {len(positions)} rows, the fold mesh has {mesh.n_vertices} vertices")
    me = _new_mesh_data(mesh, positions, name, scene)
    ob = None
    try:
        ob = bpy.data.objects.new(name, me)
        collection.objects.link(ob)
        write_pattern_attributes(ob, mesh, scene)
        if not creases:
            ob["cf_no_creases"] = True
        write_results(
            ob, mesh, positions, fold_angles_sim=fold_angles_sim, strain_pct=strain_pct, warp_deg=warp_deg, scene=scene
        )
    except Exception:
        remove_fold_object(ob, me)
        raise
    return ob


def _new_mesh_data(
    mesh: FoldMesh, positions: np.ndarray, name: str, scene, offset: np.ndarray | None = None
) -> bpy.types.Mesh:
    """A new Mesh datablock with ``mesh``'s triangles at ``positions`` (mm), moved by ``offset`` (BU, the object's
    :func:`local_offset`); removed again if it cannot be made."""
    me = bpy.data.meshes.new(name)
    local = positions / mm_per_unit(scene) + (0.0 if offset is None else offset)
    try:
        me.from_pydata(local.tolist(), [], mesh.triangles.tolist())
        me.update()
        if len(me.edges) != len(mesh.edges):
            raise ValueError(
                f"fold mesh '{name}': Blender made {len(me.edges)} edges from {mesh.n_faces} triangles, "
                f"the fold mesh lists {len(mesh.edges)} (an edge outside every triangle?)"
            )
    except Exception:
        bpy.data.meshes.remove(me)
        raise
    return me


def replace_fold_mesh(
    ob: bpy.types.Object,
    mesh: FoldMesh,
    positions: np.ndarray,
    *,
    scene: bpy.types.Scene | None = None,
    **results,
) -> None:
    """Give the existing fold object ``ob`` a new mesh (a rebuilt pattern): the object, its name, location,
    modifiers and settings stay; the old mesh datablock (with any baked keys) is deleted. Atomic: if writing the
    new mesh fails, ``ob`` keeps its old mesh."""
    positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    old = ob.data
    offset = local_offset(ob)  # the origin as the designer left it, measured on the old mesh
    me = _new_mesh_data(mesh, positions, old.name, scene, offset)
    for mat in old.materials:
        me.materials.append(mat)
    kept = origin_state(ob)
    ob.data = me
    remember_local(ob, offset)
    try:
        write_pattern_attributes(ob, mesh, scene)
        ob.pop("cf_crease_topology", None)
        write_results(ob, mesh, positions, scene=scene, **results)
    except Exception:
        ob.data = old
        restore_origin_state(ob, kept)
        bpy.data.meshes.remove(me)
        raise
    name = old.name
    if old.users == 0:
        bpy.data.meshes.remove(old)
        me.name = name


def remove_fold_object(ob: bpy.types.Object | None, me: bpy.types.Mesh | None = None) -> None:
    """Delete a fold object, its mesh and its crease-curve children, and the materials they alone used (used to undo
    a failed write: the crease curves' material was left behind)."""
    materials = []
    if ob is not None:
        me = me or ob.data
        for child in list(_crease_curve_objects(ob).values()):
            cu = child.data
            materials += [m for m in cu.materials if m is not None]
            bpy.data.objects.remove(child)
            if cu.users == 0:
                bpy.data.curves.remove(cu)
        bpy.data.objects.remove(ob)
    if me is not None:
        materials += [m for m in me.materials if m is not None]
        if me.users == 0:
            bpy.data.meshes.remove(me)
    for mat in {m.name: m for m in materials}.values():
        if mat.users == 0:
            bpy.data.materials.remove(mat)


def write_pattern_attributes(ob: bpy.types.Object, mesh: FoldMesh, scene: bpy.types.Scene | None = None) -> None:
    """Store the flat pattern on ``ob``'s mesh: ``cf_flat``, ``cf_assignment``, ``cf_fold_angle``, ``cf_face``...
    and the unit it is in (:data:`FLAT_UNIT_KEY`)."""
    me = ob.data
    me[FLAT_UNIT_KEY] = mm_per_unit(scene)
    perm = blender_edge_order(me, mesh)
    codes = assignment_codes(mesh.assignments)
    _set_attr(me, "cf_flat", "FLOAT2", "POINT", mesh.vertices.astype(np.float32), "vector")
    me[EXACT_FLAT_KEY] = np.asarray(mesh.vertices, dtype=np.float64).ravel().tolist()
    _set_attr(me, "cf_assignment", "INT8", "EDGE", codes[perm].astype(np.int32), "value")
    _set_attr(me, "cf_fold_angle", "FLOAT", "EDGE", mesh.fold_angles[perm].astype(np.float32), "value")
    me[EXACT_ANGLE_KEY] = np.asarray(mesh.fold_angles[perm], dtype=np.float64).tolist()
    _set_attr(me, "cf_from_curve", "BOOLEAN", "EDGE", mesh.edge_from_curve[perm], "value")
    _set_attr(me, "cf_polyline", "INT", "EDGE", mesh.edge_polyline[perm].astype(np.int32), "value")
    tri_order = _blender_face_order(me, mesh)
    _set_attr(me, "cf_face", "INT", "FACE", mesh.triangle_face[tri_order].astype(np.int32), "value")
    _paper_shading(me, mesh.assignments[perm])
    me["cf_mesh_type"] = mesh.mesh_type
    me["cf_swaps"] = int(mesh.swaps)
    me["cf_sources"] = list(mesh.sources)


def _paper_shading(me: bpy.types.Mesh, assignments: np.ndarray) -> None:
    """Shade the sheet as paper: smooth across the panels (a curved panel is a smooth surface, its triangles only
    follow the rulings), sharp along creases, borders and cuts (Blender's ``sharp_edge``; ``sharp_face`` removed:
    every face smooth). Flat-shaded, curved paper rendered faceted, and the glTF/OBJ exporters split every vertex
    per face (wavy_pleats: 1,920 vertices for 371)."""
    _set_attr(me, "sharp_edge", "BOOLEAN", "EDGE", np.isin(assignments, ("M", "V", "B", "C", "U")), "value")
    sharp_face = me.attributes.get("sharp_face")
    if sharp_face is not None:
        me.attributes.remove(sharp_face)


def _blender_face_order(me: bpy.types.Mesh, mesh: FoldMesh) -> np.ndarray:
    """Blender polygon i is FoldMesh triangle i (``from_pydata`` keeps face order); checked, not assumed."""
    if len(me.polygons) != mesh.n_faces:
        raise ValueError(f"mesh '{me.name}' has {len(me.polygons)} faces, the fold mesh has {mesh.n_faces}")
    return np.arange(mesh.n_faces)


OFFSET_KEY, PROBE_KEY = "cf_local_offset", "cf_local_probe"
"""A fold object's vertices sit at the engine's positions (mm, the pattern's frame) ÷ the unit, plus ``cf_local_offset``
(Blender units): zero until the designer moves the object's origin (Set Origin, or Snap ▸ Cursor to Selected and
Origin to 3D Cursor), which shifts every vertex the other way. ``cf_local_probe`` holds :data:`PROBES` vertices as
last written; a later write or read finds the shift from them (:func:`local_offset`). Re-folding an object whose
origin had been set to its geometry moved the mesh away by the shift (83 mm on the single-curve example)."""

PROBES = 8
"""Vertices (spread over the mesh's order) whose move tells an origin shift: all of them by the same vector (a few
edited vertices are not one; a review session's edit of one vertex was taken for a shift of the whole mesh)."""

SHIFT_FRACTION = 1e-4
"""A common move of the probe vertices by more than this fraction of the mesh's size since the last write is an
origin shift."""


def _probe_indices(n: int) -> np.ndarray:
    return np.unique(np.linspace(0, n - 1, min(PROBES, n)).astype(np.int64)) if n else np.zeros(0, dtype=np.int64)


def local_coordinates(ob: bpy.types.Object) -> np.ndarray:
    """``ob``'s vertices as stored (the ``position`` attribute), ``(n, 3)`` Blender units, float64."""
    co = np.empty(3 * len(ob.data.vertices), dtype=np.float32)
    ob.data.attributes["position"].data.foreach_get("vector", co)
    return co.reshape(-1, 3).astype(np.float64)


def local_offset(ob: bpy.types.Object, co: np.ndarray | None = None) -> np.ndarray:
    """The offset (BU) of ``ob``'s vertices from the engine's positions ÷ unit (:data:`OFFSET_KEY`), with any move
    of its origin since the last write added: the move of the probe vertices, where most of them moved alike (an
    origin shift moves all). Reads only: a write records it (:func:`remember_local`), so a cancelled job leaves the
    object's properties as they were. ``co``: its :func:`local_coordinates`, if the caller has them already."""
    offset = np.array(ob.get(OFFSET_KEY, (0.0, 0.0, 0.0)), dtype=np.float64)
    probe = ob.get(PROBE_KEY)
    n = len(ob.data.vertices)
    idx = _probe_indices(n)
    if probe is None or len(probe) != 3 * len(idx) or n == 0:
        return offset
    co = local_coordinates(ob) if co is None else co
    moves = co[idx] - np.array(probe, dtype=np.float64).reshape(-1, 3)
    shift = np.median(moves, axis=0)
    size = float(np.ptp(co, axis=0).max()) or 1.0
    alike = np.abs(moves - shift).max(axis=1) <= 1e-6 * size
    if np.abs(shift).max() > SHIFT_FRACTION * size and alike.sum() > len(idx) // 2:
        return offset + shift
    return offset


def child_points(child: bpy.types.Object, co: np.ndarray) -> np.ndarray:
    """Points ``co`` (``(k, 3)``, the fold object's space) in the space of its crease-curve ``child``: Set Origin on
    the fold object keeps its children in place by moving them the other way, so their frame may differ from it."""
    m = np.array(child.matrix_parent_inverse) @ np.array(child.matrix_basis)
    if np.array_equal(m, np.eye(4)):
        return co
    inv = np.linalg.inv(m)
    return (np.asarray(co, dtype=np.float64) @ inv[:3, :3].T + inv[:3, 3]).astype(np.float32)


def remember_local(ob: bpy.types.Object, offset: np.ndarray, co: np.ndarray | None = None) -> None:
    """Record that ``ob``'s vertices were just written as ``co`` (BU; read if not given) with the origin ``offset``
    (:data:`OFFSET_KEY`, :data:`PROBE_KEY`)."""
    co = local_coordinates(ob) if co is None else np.asarray(co, dtype=np.float32).astype(np.float64)
    ob[OFFSET_KEY] = [float(x) for x in offset]
    ob[PROBE_KEY] = co[_probe_indices(len(co))].ravel().tolist()


def origin_state(ob: bpy.types.Object) -> dict[str, list[float] | None]:
    """``ob``'s origin offset and probe as they are (copies: an ID property array read from the object is a view of
    it), for :func:`restore_origin_state` after a write that is undone (a preview, a failed mesh swap)."""
    return {key: None if ob.get(key) is None else [float(x) for x in ob[key]] for key in (OFFSET_KEY, PROBE_KEY)}


def restore_origin_state(ob: bpy.types.Object, state: dict[str, list[float] | None]) -> None:
    """Put back what :func:`origin_state` took."""
    for key, value in state.items():
        if value is None:
            ob.pop(key, None)
        else:
            ob[key] = value


def engine_positions(ob: bpy.types.Object, scene: bpy.types.Scene | None = None) -> np.ndarray:
    """``ob``'s vertex positions in the engine's frame (``(n, 3)`` mm): as stored, less the origin offset."""
    co = local_coordinates(ob)  # read once: the offset is measured on the same vertices
    return (co - local_offset(ob, co)) * mm_per_unit(scene)


def update_positions(
    ob: bpy.types.Object, positions: np.ndarray, *, scene: bpy.types.Scene | None = None
) -> np.ndarray:
    """Move ``ob``'s vertices to ``positions`` (``(n, 3)`` mm); writes the Basis key when the mesh has shape keys.
    Returns where the vertices go (object space, float64, before the float32 rounding of the write).

    Uses the fast float32 ``foreach_set`` paths (``attributes['position']`` / ``key.points``). The crease-curve
    children follow.
    """
    me = ob.data
    origin = local_offset(ob)
    local = np.asarray(positions, dtype=np.float64).reshape(-1, 3) / mm_per_unit(scene) + origin
    co = local.astype(np.float32)
    if len(co) != len(me.vertices):
        raise ValueError(f"object '{ob.name}' has {len(me.vertices)} vertices, got {len(co)} positions")
    if me.shape_keys is not None:
        me.shape_keys.reference_key.points.foreach_set("co", co.ravel())
    me.attributes["position"].data.foreach_set("vector", co.ravel())
    me.update()
    for child in _crease_curve_objects(ob).values():
        idx = crease_point_indices(child)
        pts = np.ones((len(idx), 4), dtype=np.float32)
        pts[:, :3] = child_points(child, co[idx])
        offset = 0
        for sp in child.data.splines:
            k = len(sp.points)
            sp.points.foreach_set("co", pts[offset : offset + k].ravel())
            offset += k
        child.data.update_tag()
    remember_local(ob, origin, co)
    return local


def write_results(
    ob: bpy.types.Object,
    mesh: FoldMesh,
    positions: np.ndarray,
    *,
    fold_angles_sim: np.ndarray | None = None,
    strain_pct: np.ndarray | None = None,
    warp_deg: np.ndarray | None = None,
    scene: bpy.types.Scene | None = None,
) -> None:
    """Write a solve's results onto ``ob``: positions, simulated fold angles, strain and warp colours, creases.

    ``fold_angles_sim`` is per FoldMesh edge (deg), ``strain_pct`` per vertex (percent), ``warp_deg`` per triangle
    or per vertex (degrees); missing ones are left as they were.
    """
    me = ob.data
    co = update_positions(ob, positions, scene=scene)  # object space, its origin's offset in
    if fold_angles_sim is not None:
        perm = blender_edge_order(me, mesh)
        sim = np.asarray(fold_angles_sim, dtype=np.float32)[perm]
        _set_attr(me, "cf_fold_angle_sim", "FLOAT", "EDGE", sim, "value")
    if strain_pct is not None:
        s = np.asarray(strain_pct, dtype=np.float64).reshape(-1)
        _set_attr(me, "cf_strain_pct", "FLOAT", "POINT", s.astype(np.float32), "value")
        write_colours(me, "cf_strain", s, STRAIN_CLIP_PCT)
    if warp_deg is not None:
        w = np.asarray(warp_deg, dtype=np.float64).reshape(-1)
        domain = "FACE" if len(w) == mesh.n_faces else "POINT"
        _set_attr(me, "cf_warp_deg", "FLOAT", domain, w.astype(np.float32), "value")
        write_colours(me, "cf_warp", w, WARP_CLIP_DEG)
    if me.color_attributes.get("cf_strain") is not None and me.color_attributes.active_color is None:
        me.color_attributes.active_color = me.color_attributes["cf_strain"]
    if ob.get("cf_no_creases"):
        return
    if not _crease_curve_objects(ob) or ob.get("cf_crease_topology") != _topology_key(mesh):
        _write_crease_curves(ob, mesh, co)
        ob["cf_crease_topology"] = _topology_key(mesh)


def write_colours(me: bpy.types.Mesh, name: str, values: np.ndarray, clip: float) -> None:
    """Write per-vertex or per-triangle ``values`` as a FLOAT_COLOR colour attribute the viewport can show.

    Per-triangle values go to the CORNER domain (each triangle's three corners), because face-domain colours are
    not colour attributes in Blender and cannot be displayed."""
    v = np.asarray(values, dtype=np.float64).reshape(-1)
    colours = heat_colours(v, clip)
    if len(v) == len(me.vertices):
        _set_attr(me, name, "FLOAT_COLOR", "POINT", colours, "color")
    elif len(v) == len(me.polygons) and len(me.loops) == 3 * len(me.polygons):
        _set_attr(me, name, "FLOAT_COLOR", "CORNER", np.repeat(colours, 3, axis=0), "color")
    else:
        raise ValueError(f"mesh '{me.name}': {len(v)} values for '{name}' match neither vertices nor triangles")


def _topology_key(mesh: FoldMesh) -> str:
    return f"{mesh.n_vertices}:{len(mesh.edges)}:{int(np.count_nonzero(np.isin(mesh.assignments, ('M', 'V'))))}"


def read_fold_mesh(ob: bpy.types.Object) -> FoldMesh:
    """Rebuild the flat :class:`FoldMesh` stored on a fold object (inverse of :func:`create_fold_object`).

    Edges come back in the order a built mesh has them (:func:`_sorted_edges`); the crease-pattern face loops are
    recovered from ``cf_face`` (the outer boundary of each group of triangles). Raises ``ValueError`` naming the
    object when an attribute is missing.
    """
    if ob is None or ob.type != "MESH":
        raise ValueError(f"'{getattr(ob, 'name', None)}' is not a mesh object")
    me = ob.data
    n, e, t = len(me.vertices), len(me.edges), len(me.polygons)
    flat = _exact(me, EXACT_FLAT_KEY, _get_attr(me, "cf_flat", "vector", np.float32, n, 2)) * flat_rescale(me)
    edges, order = _sorted_edges(me)
    loops = np.empty(len(me.loops), dtype=np.int64)
    me.loops.foreach_get("vertex_index", loops)
    sizes = np.empty(t, dtype=np.int64)
    me.polygons.foreach_get("loop_total", sizes)
    if t and not np.all(sizes == 3):
        raise ValueError(f"mesh '{me.name}' has non-triangle faces: was it edited after folding?")
    triangles = loops.reshape(-1, 3)
    codes = _get_attr(me, "cf_assignment", "value", np.int32, e)[order]
    angles = _exact(me, EXACT_ANGLE_KEY, _get_attr(me, "cf_fold_angle", "value", np.float32, e))[order]
    from_curve = _get_attr(me, "cf_from_curve", "value", bool, e)[order]
    polyline = _get_attr(me, "cf_polyline", "value", np.int32, e).astype(np.int64)[order]
    tri_face = _get_attr(me, "cf_face", "value", np.int32, t).astype(np.int64)
    assignments = np.array(ASSIGNMENTS)[np.clip(codes, 0, len(ASSIGNMENTS) - 1)]
    return FoldMesh(
        vertices=flat,
        triangles=triangles,
        edges=edges,
        assignments=assignments,
        fold_angles=angles,
        edge_from_curve=from_curve,
        edge_polyline=polyline,
        triangle_face=tri_face,
        faces=face_loops(triangles, tri_face),
        mesh_type=str(me.get("cf_mesh_type", "ruling")),
        swaps=int(me.get("cf_swaps", 0)),
        sources=[str(s) for s in me.get("cf_sources", [])],
    )


def face_loops(triangles: np.ndarray, triangle_face: np.ndarray) -> list[np.ndarray]:
    """Counter-clockwise outer boundary loop of each crease-pattern face (a group of triangles with one label).

    A directed triangle side belongs to the boundary when its reverse is not a side of the same face; the sides are
    then chained. Faces with holes keep their longest loop.
    """
    tri = np.asarray(triangles, dtype=np.int64)
    labels = np.asarray(triangle_face, dtype=np.int64)
    if not len(tri):
        return []
    half = np.stack([tri, np.roll(tri, -1, axis=1)], axis=2).reshape(-1, 2)
    face_of = np.repeat(labels, 3)
    n = int(tri.max()) + 1
    keys = (face_of * n + half[:, 0]) * n + half[:, 1]
    rkeys = (face_of * n + half[:, 1]) * n + half[:, 0]
    boundary = ~np.isin(keys, rkeys)
    out: list[np.ndarray] = []
    for f in range(int(labels.max()) + 1):
        sel = half[boundary & (face_of == f)]
        if not len(sel):
            out.append(np.zeros(0, dtype=np.int64))
            continue
        nxt = dict(zip(sel[:, 0].tolist(), sel[:, 1].tolist(), strict=False))
        best: list[int] = []
        seen: set[int] = set()
        for start in sel[:, 0].tolist():
            if start in seen:
                continue
            loop = [start]
            seen.add(start)
            v = nxt[start]
            while v != start and v in nxt and v not in seen and len(loop) <= len(sel):
                loop.append(v)
                seen.add(v)
                v = nxt[v]
            if len(loop) > len(best):
                best = loop
        out.append(np.array(best, dtype=np.int64))
    return out


# ------------------------------------------------------------------------------------------------ naming, placing

PLACEMENT_GAP = 0.15
"""Gap between a new folded mesh and what it is placed beside, as a fraction of the new mesh's width."""


def fold_object_name(collection: bpy.types.Collection | None, sources: list[bpy.types.Object]) -> str:
    """``"<pattern> Folded"``: the pattern is the folded collection, else the one collection every source curve is
    in (an import's collection is named after its file), else the first curve (Blender adds ``.001`` on repeats)."""
    if collection is not None:
        return f"{collection.name} Folded"
    shared = None
    for ob in sources:
        colls = {c.name for c in ob.users_collection if not c.is_embedded_data}  # not a scene's own
        shared = colls if shared is None else shared & colls
    if shared:
        return f"{sorted(shared)[0]} Folded"
    return f"{sources[0].name} Folded" if sources else "Folded"


def _world_box(ob: bpy.types.Object) -> np.ndarray:
    """``[[xmin, ymin], [xmax, ymax]]`` of the object's bounding box in world space."""
    m = np.array(ob.matrix_world, dtype=np.float64)
    corners = np.array([tuple(c) for c in ob.bound_box], dtype=np.float64) @ m[:3, :3].T + m[:3, 3]
    return np.array([corners[:, :2].min(axis=0), corners[:, :2].max(axis=0)])


def place_beside(ob: bpy.types.Object, sources: list[bpy.types.Object], view_layer=None) -> None:
    """Move the new folded mesh ``ob`` to the right of its source curves and of every folded mesh already made from
    them, with a gap, so a new Fold never overlaps the last one; y is aligned with the curves. If that spot overlaps
    another mesh or curve in the view layer (a second sheet drawn beside the first), it moves further right, past
    what it meets (a helper's fold of one of two sheets side by side landed on the other's curves)."""
    view_layer = view_layer or bpy.context.view_layer
    view_layer.update()
    source_set = {s.name for s in sources}
    others = [s for s in sources if s is not None]
    for other in bpy.data.objects:
        props = getattr(other, "curved_fold_mesh", None)
        if other is ob or props is None or not props.is_fold_mesh:
            continue
        if any(s.object is not None and s.object.name in source_set for s in props.sources):
            others.append(other)
    if not others:
        return
    boxes = np.array([_world_box(o) for o in others])
    right, bottom = float(boxes[:, 1, 0].max()), float(boxes[:, 0, 1].min())
    own = _world_box(ob)
    width = float(own[1, 0] - own[0, 0])
    dx = right + PLACEMENT_GAP * width - float(own[0, 0])
    dy = bottom - float(own[0, 1])
    # and clear of everything else drawn there (a second sheet beside the first): further right, past what it meets
    placed = set(others) | {ob}
    blockers = [
        o for o in view_layer.objects if o.type in {"MESH", "CURVE"} and o not in placed and o.parent not in placed
    ]
    if blockers:
        walls = np.array([_world_box(o) for o in blockers])
        size = own[1] - own[0]
        for _ in range(len(blockers)):
            lo = own[0] + (dx, dy)
            hit = np.all((walls[:, 0] < lo + size) & (walls[:, 1] > lo), axis=1)
            if not hit.any():
                break
            dx = float(walls[hit, 1, 0].max()) + PLACEMENT_GAP * width - float(own[0, 0])
    ob.location.x += dx
    ob.location.y += dy
