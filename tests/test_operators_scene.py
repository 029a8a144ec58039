"""Scene-side writers behind the operators (scene/mesh_object.py, bake.py, export.py, import_curves.py).

These run against real Blender data (the bpy module) with hand-made FoldMesh arrays, so they do not depend on the
triangulator or the solver; the operator tests (tests/test_operators.py) go through the whole pipeline.
"""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from curved_fold.core.mesh.fold_mesh import FoldMesh  # noqa: E402
from curved_fold.core.pattern.model import CreasePattern  # noqa: E402
from curved_fold.core.pattern.polylines import curves_from_pattern  # noqa: E402
from curved_fold.scene import bake, export, mesh_object  # noqa: E402


@pytest.fixture
def empty_scene():
    bpy.ops.wm.read_homefile(use_empty=True)
    yield bpy.context.scene


def grid_mesh(nx: int = 5, ny: int = 3, width: float = 100.0, height: float = 40.0) -> FoldMesh:
    """A rectangle triangulated as a grid with a valley crease (90°) down the middle column and a mountain
    (−60°) along the middle row's left half; border edges B, the rest F. Triangles counter-clockwise."""
    xs, ys = np.linspace(0, width, nx), np.linspace(0, height, ny)
    X, Y = np.meshgrid(xs, ys)
    verts = np.column_stack([X.ravel(), Y.ravel()])
    tris = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            a, b, c, d = j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i
            tris += [[a, b, c], [a, c, d]]
    tris = np.array(tris)
    e = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    edges = np.unique(e, axis=0)
    x0, x1 = verts[edges[:, 0]], verts[edges[:, 1]]
    mid_x, mid_y = xs[nx // 2], ys[ny // 2]
    assign = np.full(len(edges), "F")
    angles = np.zeros(len(edges))
    border = (
        ((x0[:, 0] == 0) & (x1[:, 0] == 0))
        | ((x0[:, 0] == width) & (x1[:, 0] == width))
        | ((x0[:, 1] == 0) & (x1[:, 1] == 0))
        | ((x0[:, 1] == height) & (x1[:, 1] == height))
    )
    valley = (x0[:, 0] == mid_x) & (x1[:, 0] == mid_x)
    mountain = (x0[:, 1] == mid_y) & (x1[:, 1] == mid_y) & (np.maximum(x0[:, 0], x1[:, 0]) <= mid_x)
    assign[border], angles[border] = "B", np.nan
    assign[valley], angles[valley] = "V", 90.0
    assign[mountain], angles[mountain] = "M", -60.0
    poly = np.full(len(edges), -1)
    poly[border], poly[valley], poly[mountain] = 0, 1, 2
    return FoldMesh(
        vertices=verts,
        triangles=tris,
        edges=edges,
        assignments=assign,
        fold_angles=angles,
        edge_from_curve=valley | mountain,
        edge_polyline=poly,
        triangle_face=np.zeros(len(tris), dtype=int),
        faces=[],
        sources=["border", "valley curve", "mountain curve"],
    )


def folded(mesh: FoldMesh, t: float) -> np.ndarray:
    """A smooth made-up 3D shape per parameter t (the writers do not care that it is not a solver result)."""
    p = mesh.vertices_3d
    p[:, 2] = t * 10.0 * np.sin(p[:, 0] / 30.0) + t * 0.1 * p[:, 1]
    return p


def evaluated_positions_mm(ob) -> np.ndarray:
    dg = bpy.context.evaluated_depsgraph_get()
    ev = ob.evaluated_get(dg)
    co = np.empty(len(ev.data.vertices) * 3, dtype=np.float32)
    ev.data.attributes["position"].data.foreach_get("vector", co)
    return co.reshape(-1, 3).astype(np.float64) * mesh_object.mm_per_unit()


def test_create_fold_object_writes_attributes_and_reads_back(empty_scene):
    mesh = grid_mesh()
    pos = folded(mesh, 1.0)
    strain = np.linspace(0, 10, mesh.n_vertices)
    warp = np.linspace(0, 2 * mesh_object.WARP_CLIP_DEG, mesh.n_faces)
    ob = mesh_object.create_fold_object(
        mesh,
        pos,
        "Fold",
        empty_scene.collection,
        fold_angles_sim=mesh.fold_angles * 0.5,
        strain_pct=strain,
        warp_deg=warp,
    )
    me = ob.data
    # Warp colours are per triangle on its corners (face-domain colours cannot be shown by the viewport).
    cw = me.color_attributes["cf_warp"]
    assert cw.domain == "CORNER" and me.color_attributes["cf_strain"].domain == "POINT"
    corner = np.empty(4 * len(me.loops), dtype=np.float32)
    cw.data.foreach_get("color", corner)
    corner = corner.reshape(-1, 3, 4)
    assert np.all(corner[:, 0] == corner[:, 2]) and corner[0, 0, 2] > 0.9 and corner[-1, 0, 0] > 0.9
    assert (len(me.vertices), len(me.edges), len(me.polygons)) == (mesh.n_vertices, len(mesh.edges), mesh.n_faces)
    np.testing.assert_allclose(evaluated_positions_mm(ob), pos, atol=1e-3)
    back = mesh_object.read_fold_mesh(ob)
    # Same edge set with the same assignment/angle per edge, whatever Blender's edge order.
    n = mesh.n_vertices
    k0, k1 = mesh.edges[:, 0] * n + mesh.edges[:, 1], back.edges[:, 0] * n + back.edges[:, 1]
    o0, o1 = np.argsort(k0), np.argsort(k1)
    np.testing.assert_array_equal(k0[o0], k1[o1])
    np.testing.assert_array_equal(mesh.assignments[o0], back.assignments[o1])
    np.testing.assert_array_equal(mesh.fold_angles[o0], back.fold_angles[o1])  # nan == nan here
    np.testing.assert_array_equal(mesh.edge_polyline[o0], back.edge_polyline[o1])
    np.testing.assert_array_equal(back.triangles, mesh.triangles)
    np.testing.assert_allclose(back.vertices, mesh.vertices, atol=1e-5)
    assert back.sources == mesh.sources
    # The whole rectangle is one face: its loop is the 12 boundary vertices, counter-clockwise.
    assert len(back.faces) == 1 and len(back.faces[0]) == 2 * (5 + 3) - 4
    loop = mesh.vertices[back.faces[0]]
    assert 0.5 * np.sum(loop[:, 0] * np.roll(loop[:, 1], -1) - np.roll(loop[:, 0], -1) * loop[:, 1]) > 0
    np.testing.assert_array_equal(back.edges, mesh.edges)  # and in the built mesh's order (a Re-fold is the Fold)
    sim = mesh_object.simulated_fold_angles(ob)  # in read_fold_mesh's order
    np.testing.assert_array_equal(np.isnan(sim), np.isnan(back.fold_angles))
    np.testing.assert_allclose(sim[~np.isnan(sim)], 0.5 * back.fold_angles[~np.isnan(sim)], atol=1e-5)
    # Strain colours: blue at 0 %, red at >= 5 %.
    col = np.empty(n * 4, dtype=np.float32)
    me.attributes["cf_strain"].data.foreach_get("color", col)
    col = col.reshape(-1, 4)
    assert col[0, 2] > 0.9 and col[0, 0] < 0.1 and col[-1, 0] > 0.9 and col[-1, 2] < 0.1
    # Crease curves: one red mountain child, one blue valley child, points on the folded crease vertices.
    roles = {c["cf_crease_role"]: c for c in ob.children}
    assert set(roles) == {"M", "V"}
    v = roles["V"]
    pts = np.array([p.co[:3] for sp in v.data.splines for p in sp.points]) * mesh_object.mm_per_unit()
    np.testing.assert_allclose(pts, pos[mesh_object.crease_point_indices(v)], atol=1e-3)


def test_create_fold_object_failure_leaves_nothing(empty_scene):
    mesh = grid_mesh()
    before = (len(bpy.data.objects), len(bpy.data.meshes), len(bpy.data.curves))
    with pytest.raises(ValueError, match="positions"):
        mesh_object.create_fold_object(mesh, np.zeros((3, 3)), "Bad", empty_scene.collection)
    bad = grid_mesh()
    bad.assignments[0] = "X"  # unknown assignment: fails after the mesh datablock exists
    with pytest.raises(ValueError, match="unknown assignment 'X'"):
        mesh_object.create_fold_object(bad, folded(bad, 1), "Bad", empty_scene.collection)
    assert (len(bpy.data.objects), len(bpy.data.meshes), len(bpy.data.curves)) == before


def test_update_positions_with_and_without_shape_keys(empty_scene):
    mesh = grid_mesh()
    ob = mesh_object.create_fold_object(mesh, folded(mesh, 0.2), "Fold", empty_scene.collection)
    mesh_object.update_positions(ob, folded(mesh, 0.7))
    np.testing.assert_allclose(evaluated_positions_mm(ob), folded(mesh, 0.7), atol=1e-3)
    ob.shape_key_add(name="Basis", from_mix=False)
    mesh_object.update_positions(ob, folded(mesh, 0.4))
    np.testing.assert_allclose(evaluated_positions_mm(ob), folded(mesh, 0.4), atol=1e-3)


def test_bake_ten_frames_keys_values_and_positions(empty_scene):
    mesh = grid_mesh()
    ob = mesh_object.create_fold_object(mesh, folded(mesh, 0.0), "Fold", empty_scene.collection)
    frames = list(range(1, 11))
    shapes = [folded(mesh, f / 10) for f in frames]
    names = bake.bake_shape_keys(ob, frames, shapes)
    keys = ob.data.shape_keys
    assert names == [f"cf_frame_{f:04d}" for f in frames] and bake.baked_frames(ob) == frames
    assert [k.name for k in keys.key_blocks] == ["Basis", *names]
    assert all(k.value == 0.0 for k in keys.key_blocks[1:])
    fcurves = bake._fcurves(keys)
    assert len(fcurves) == 10 and all(kp.interpolation == "LINEAR" for fc in fcurves for kp in fc.keyframe_points)
    for f, shape in zip(frames, shapes, strict=True):
        empty_scene.frame_set(f)
        np.testing.assert_allclose(evaluated_positions_mm(ob), shape, atol=2e-3)
    empty_scene.frame_set(4, subframe=0.5)  # linear blend between neighbouring frames
    np.testing.assert_allclose(evaluated_positions_mm(ob), 0.5 * (shapes[3] + shapes[4]), atol=2e-3)
    empty_scene.frame_set(30)  # after the range the last frame holds
    np.testing.assert_allclose(evaluated_positions_mm(ob), shapes[-1], atol=2e-3)
    for child in ob.children:  # crease curves carry the same keys
        assert len(child.data.shape_keys.key_blocks) == 11
    assert bake.clear_bake(ob) == 10
    assert ob.data.shape_keys is None and all(c.data.shape_keys is None for c in ob.children)


def test_bake_rejects_bad_frames_and_leaves_object_as_before(empty_scene):
    mesh = grid_mesh()
    ob = mesh_object.create_fold_object(mesh, folded(mesh, 0.3), "Fold", empty_scene.collection)
    shapes = [folded(mesh, 0.1), folded(mesh, 0.2)]
    shapes[1][3, 2] = np.nan
    with pytest.raises(ValueError, match="frame 2: positions must be finite"):
        bake.bake_shape_keys(ob, [1, 2], shapes)
    with pytest.raises(ValueError, match="distinct"):
        bake.bake_shape_keys(ob, [1, 1], [folded(mesh, 0.1)] * 2)
    assert ob.data.shape_keys is None and len(bpy.data.actions) == 0


@pytest.mark.parametrize("suffix", [".obj", ".stl", ".glb", ".blend"])
def test_export_through_blender_reimports_and_leaves_scene(empty_scene, tmp_path, suffix):
    mesh = grid_mesh()
    frames = [folded(mesh, t) for t in (0.0, 0.5, 1.0)]
    before = (set(bpy.data.objects), set(bpy.data.meshes), len(bpy.data.scenes), bpy.context.scene)
    path = export.export_folded_file(tmp_path / f"fold{suffix}", mesh, frames)
    assert path.stat().st_size > 0
    assert (set(bpy.data.objects), set(bpy.data.meshes), len(bpy.data.scenes), bpy.context.scene) == before
    if suffix == ".obj":
        bpy.ops.wm.obj_import(filepath=str(path))
    elif suffix == ".stl":
        bpy.ops.wm.stl_import(filepath=str(path))
    elif suffix == ".glb":
        bpy.ops.import_scene.gltf(filepath=str(path))
        # Morph targets + a weights animation: read the GLB's JSON chunk directly.
        raw = path.read_bytes()
        (json_len,) = struct.unpack_from("<I", raw, 12)
        doc = json.loads(raw[20 : 20 + json_len])
        assert len(doc["meshes"][0]["primitives"][0]["targets"]) == 3
        assert any(ch["target"]["path"] == "weights" for a in doc["animations"] for ch in a["channels"])
    else:
        with bpy.data.libraries.load(str(path)) as (src, dst):
            dst.objects = list(src.objects)
        for ob in dst.objects:
            empty_scene.collection.objects.link(ob)
    new = [ob for ob in bpy.data.objects if ob not in before[0] and ob.type == "MESH"]
    assert len(new) == 1
    got = new[0].data
    if suffix in (".stl", ".glb"):  # these split vertices per face / per normal
        assert len(got.polygons) == mesh.n_faces
        co = np.array([v.co[:] for v in got.vertices]) * mesh_object.mm_per_unit()
        if suffix == ".glb":  # base mesh = flat sheet, last morph target = last frame (importer turns y-up to z-up)
            np.testing.assert_allclose(np.unique(np.round(co, 2), axis=0), np.unique(np.round(frames[0], 2), axis=0))
            last = got.shape_keys.key_blocks[-1]
            co = np.array([p.co[:] for p in last.data]) * mesh_object.mm_per_unit()
            np.testing.assert_allclose(np.unique(np.round(co, 2), axis=0), np.unique(np.round(frames[-1], 2), axis=0))
    else:
        assert len(got.vertices) == mesh.n_vertices and len(got.polygons) == mesh.n_faces
    if suffix == ".blend":
        assert len(got.shape_keys.key_blocks) == 4
        empty_scene.frame_set(3)
        np.testing.assert_allclose(evaluated_positions_mm(new[0]), frames[-1], atol=2e-3)


def test_export_svg_origami_simulator_convention(tmp_path):
    mesh = grid_mesh()
    text = export.write_pattern_svg(tmp_path / "cp.svg", mesh).read_text()
    assert 'width="100mm" height="40mm"' in text
    lines = [ln for ln in text.splitlines() if ln.startswith("<polyline")]
    strokes = sorted(ln.split('stroke="')[1][:7] for ln in lines)
    assert strokes == ["#000000", "#0000ff", "#ff0000"]  # one closed border chain, one valley, one mountain
    valley = next(ln for ln in lines if "#0000ff" in ln)
    mountain = next(ln for ln in lines if "#ff0000" in ln)
    assert 'opacity="0.5"' in valley and 'opacity="0.3333333333333333"' in mountain  # read back: 60° exactly
    # y flipped back to SVG's y-down: the mountain row (y = 20 mm) stays at 20; the valley spans y 0..40.
    assert 'points="0,20 25,20 50,20"' in mountain or 'points="50,20 25,20 0,20"' in mountain


def test_export_rejects_unknown_suffix(tmp_path):
    mesh = grid_mesh()
    with pytest.raises(ValueError, match=r"cannot export '\.xyz'"):
        export.export_folded_file(tmp_path / "a.xyz", mesh, folded(mesh, 1))
    with pytest.raises(ValueError, match="shape"):
        export.export_folded_file(tmp_path / "a.obj", mesh, np.zeros((4, 3)))


def test_curves_from_pattern_chains_segments():
    # An L-shaped valley polyline of 3 segments, a separate mountain segment and a closed square border.
    v = np.array([[0, 0], [10, 0], [20, 0], [20, 10], [0, 5], [5, 5], [-10, -10], [30, -10], [30, 30], [-10, 30]])
    edges = np.array([[0, 1], [1, 2], [2, 3], [4, 5], [6, 7], [7, 8], [8, 9], [9, 6]])
    pat = CreasePattern(
        vertices=v,
        edges=edges,
        assignments=list("VVVMBBBB"),
        fold_angles=[90, 90, 90, -45, np.nan, np.nan, np.nan, np.nan],
        edge_polyline=[0, 0, 0, 1, 2, 2, 2, 2],
        edge_from_curve=[0] * 8,
        sources=["valley", "mountain", "border"],
    )
    curves = curves_from_pattern(pat)
    by = {c.assignment: c for c in curves}
    assert len(curves) == 3
    assert len(by["V"].segments) == 3 and by["V"].fold_angle == 90 and not by["V"].closed
    assert by["B"].closed and len(by["B"].segments) == 4 and by["B"].fold_angle is None
    assert by["M"].fold_angle == -45 and by["M"].source == "mountain"
    ends = {tuple(by["V"].segments[0].start), tuple(by["V"].segments[-1].end)}
    assert ends == {(0.0, 0.0), (20.0, 10.0)}
