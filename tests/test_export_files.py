"""Files other tools read back (issue 15): glTF normals/material/UVs, OBJ UVs, STL in millimetres with a Solidify
thickness, the crease-pattern SVG keeping the Cut role, and the Khronos glTF validator on our GLB where node is
installed. Real bpy, a real fold of a vendored pattern."""

from __future__ import annotations

import base64
import json
import math
import os
import shutil
import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from curved_fold.core.io.reader import read_pattern  # noqa: E402
from curved_fold.core.pipeline import fold_pattern  # noqa: E402
from curved_fold.scene import export  # noqa: E402

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "origami-simulator"
DATA = Path(__file__).resolve().parent / "data"
REPO = Path(__file__).resolve().parents[1]

SLIT_SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="60mm" viewBox="0 0 100 60">
<polygon stroke="#000000" fill="none" points="0,0 100,0 100,60 0,60"/>
<polyline stroke="#00ff00" fill="none" points="30,30 50,28 70,30"/>
<line stroke="#0000ff" opacity="0.5" x1="50" y1="0" x2="50" y2="20"/>
<line stroke="#ff0000" opacity="0.5" x1="50" y1="40" x2="50" y2="60"/>
</svg>
"""


@pytest.fixture(scope="module")
def wavy():
    """wavy_pleats folded at 40 %, 70 %, 100 %: mesh and three frames (mm)."""
    pattern = read_pattern(FIXTURES / "wavy_pleats.svg")
    runs = [fold_pattern(pattern, percent=p) for p in (0.4, 0.7, 1.0)]
    return runs[-1].mesh, [r.result.positions for r in runs]


@pytest.fixture
def empty_scene():
    bpy.ops.wm.read_homefile(use_empty=True)
    yield bpy.context.scene


def read_glb(path: Path) -> tuple[dict, bytes]:
    raw = path.read_bytes()
    (json_len,) = struct.unpack_from("<I", raw, 12)
    doc = json.loads(raw[20 : 20 + json_len])
    (bin_len,) = struct.unpack_from("<I", raw, 20 + json_len)
    return doc, raw[28 + json_len : 28 + json_len + bin_len]


def accessor(doc: dict, blob: bytes, index: int) -> np.ndarray:
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    dtype = {5126: np.float32, 5125: np.uint32, 5123: np.uint16, 5121: np.uint8}[acc["componentType"]]
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[acc["type"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    stride = view.get("byteStride", 0) or width * np.dtype(dtype).itemsize
    count = acc["count"]
    rows = np.frombuffer(
        blob, dtype=np.uint8, count=stride * (count - 1) + width * np.dtype(dtype).itemsize, offset=start
    )
    out = np.lib.stride_tricks.as_strided(
        rows.view(np.uint8), shape=(count, width * np.dtype(dtype).itemsize), strides=(stride, 1)
    )
    return np.ascontiguousarray(out).view(dtype).reshape(count, width)


def face_averaged_normals(pos: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Area-weighted average of the triangle normals around each vertex, unit length."""
    a, b, c = pos[tris[:, 0]], pos[tris[:, 1]], pos[tris[:, 2]]
    fn = np.cross(b - a, c - a)
    vn = np.zeros_like(pos)
    for k in range(3):
        np.add.at(vn, tris[:, k], fn)
    return vn / np.linalg.norm(vn, axis=1, keepdims=True).clip(1e-300)


def angle_deg(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    return np.degrees(np.arccos(np.clip(np.sum(u * v, axis=1), -1, 1)))


def test_glb_normals_follow_base_and_morphs_material_is_double_sided_uvs_are_flat(empty_scene, wavy, tmp_path):
    mesh, frames = wavy
    path = export.export_folded_file(tmp_path / "w.glb", mesh, frames)
    doc, blob = read_glb(path)
    prim = doc["meshes"][0]["primitives"][0]
    pos = accessor(doc, blob, prim["attributes"]["POSITION"]).astype(np.float64)
    nrm = accessor(doc, blob, prim["attributes"]["NORMAL"]).astype(np.float64)
    tris = accessor(doc, blob, prim["indices"]).reshape(-1, 3).astype(np.int64)
    assert len(tris) == mesh.n_faces
    # paper shading: smooth across panels, sharp along creases and borders, so vertices are split only there
    # (flat shading split every vertex per face: 1,920 for wavy_pleats' 371 before the tenth pass; now 656)
    assert len(pos) < 2 * mesh.n_vertices, (len(pos), mesh.n_vertices)
    base_err = angle_deg(nrm, face_averaged_normals(pos, tris))
    assert base_err.max() <= 15.0, f"base normals off by up to {base_err.max():.1f}°"
    # every morph target moves the normals with the positions
    assert len(prim["targets"]) == 3
    for k, target in enumerate(prim["targets"]):
        assert "NORMAL" in target, f"morph target {k} has no normals"
        p = pos + accessor(doc, blob, target["POSITION"])
        n = nrm + accessor(doc, blob, target["NORMAL"])
        err = angle_deg(n, face_averaged_normals(p, tris))
        assert np.median(err) <= 5.0 and np.percentile(err, 95) <= 15.0, (k, np.percentile(err, [50, 95, 100]))
    mat = doc["materials"][prim["material"]]
    assert mat["doubleSided"] is True
    uv = accessor(doc, blob, prim["attributes"]["TEXCOORD_0"]).astype(np.float64)
    # glTF's v runs down the image: v = 1 - our v. Each exported vertex sits at a mesh vertex; compare per position.
    flat = (mesh.vertices - mesh.vertices.min(axis=0)) / np.ptp(mesh.vertices, axis=0).max()
    base_xy = np.column_stack([pos[:, 0], -pos[:, 2]]) * 1000.0
    nearest = np.argmin(((base_xy[:, None, :] - mesh.vertices[None, :, :]) ** 2).sum(-1), axis=1)
    np.testing.assert_allclose(np.column_stack([uv[:, 0], 1.0 - uv[:, 1]]), flat[nearest], atol=1e-6)
    # the last target is the last frame, in metres (glTF's y-up (x, y, z) is Blender's (x, -z, y))
    last = (pos + accessor(doc, blob, prim["targets"][-1]["POSITION"])) * 1000.0
    np.testing.assert_allclose(last[:, [0, 2, 1]] * [1, -1, 1], frames[-1][nearest], atol=1e-3 * mesh.diagonal)


def test_obj_carries_flat_uvs_and_mm_on_request(empty_scene, wavy, tmp_path):
    mesh, frames = wavy
    path = export.export_folded_file(tmp_path / "w.obj", mesh, frames[-1], unit="mm")
    lines = path.read_text().splitlines()
    v = np.array([[float(x) for x in ln.split()[1:4]] for ln in lines if ln.startswith("v ")])
    vt = np.array([[float(x) for x in ln.split()[1:3]] for ln in lines if ln.startswith("vt ")])
    assert len(vt) and vt.min() >= -1e-6 and vt.max() <= 1 + 1e-6
    size = np.ptp(v, axis=0).max()
    assert abs(size - np.ptp(frames[-1], axis=0).max()) < 1e-3 * size  # millimetres (OBJ is y-up, sizes agree)
    with pytest.raises(ValueError, match="unit 'mm' not offered for '.glb'"):
        export.export_folded_file(tmp_path / "w.glb", mesh, frames[-1], unit="mm")


def read_binary_stl(path: Path) -> np.ndarray:
    raw = path.read_bytes()
    (count,) = struct.unpack_from("<I", raw, 80)
    rec = np.frombuffer(
        raw, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]), count=count, offset=84
    )
    return rec["v"].astype(np.float64)


def test_solidify_reaches_stl_in_millimetres_and_animated_glb(empty_scene, wavy, tmp_path):
    mesh, frames = wavy
    holder = bpy.data.objects.new("Holder", bpy.data.meshes.new("Holder"))
    solid = holder.modifiers.new("Thickness", "SOLIDIFY")
    solid.thickness = 0.0005  # 0.5 mm in metres
    path = export.export_folded_file(tmp_path / "w.stl", mesh, frames[-1], modifiers_from=holder)
    tri = read_binary_stl(path)
    assert len(tri) > mesh.n_faces * 2  # both skins (and the rim)
    extent = np.ptp(tri.reshape(-1, 3), axis=0).max()
    assert abs(extent - np.ptp(frames[-1], axis=0).max()) < 2.0  # millimetres, not metres
    glb = export.export_folded_file(tmp_path / "w.glb", mesh, frames, modifiers_from=holder)
    doc, blob = read_glb(glb)
    prim = doc["meshes"][0]["primitives"][0]
    assert accessor(doc, blob, prim["indices"]).size // 3 > 2 * mesh.n_faces and len(prim["targets"]) == 3
    assert not list(bpy.data.objects) or list(bpy.data.objects) == [holder]  # the temporary scene left nothing


def test_export_follows_the_users_scene_units_turn_and_scale(empty_scene, wavy, tmp_path):
    """The source object's modifiers are copied into the export's own scene (unit scale 1, metres): a Solidify of
    0.5 in a scene of 1 unit = 1 mm came out 0.5 m thick, the model ~1000× too big. Its rotation and scale were
    left out (a model turned to lie flat, or scaled up, exported as folded)."""
    mesh, frames = wavy
    empty_scene.unit_settings.scale_length = 0.001  # 1 BU = 1 mm
    holder = bpy.data.objects.new("Holder", bpy.data.meshes.new("Holder"))
    empty_scene.collection.objects.link(holder)
    holder.modifiers.new("Thickness", "SOLIDIFY").thickness = 0.5  # 0.5 mm
    path = export.export_folded_file(tmp_path / "w.stl", mesh, frames[-1], modifiers_from=holder)
    extent = np.ptp(read_binary_stl(path).reshape(-1, 3), axis=0)
    assert np.all(np.abs(extent - np.ptp(frames[-1], axis=0)) < 2.0), extent  # millimetres of paper, not metres
    holder.modifiers.clear()
    holder.rotation_euler = (np.pi / 2, 0.0, 0.0)
    holder.scale = (2.0, 2.0, 2.0)
    bpy.context.view_layer.update()
    path = export.export_folded_file(tmp_path / "t.stl", mesh, frames[-1], modifiers_from=holder)
    turned = 2.0 * frames[-1] @ np.array(holder.matrix_world.to_3x3().normalized()).T
    np.testing.assert_allclose(np.ptp(read_binary_stl(path).reshape(-1, 3), axis=0), np.ptp(turned, axis=0), atol=1e-3)


def test_blend_export_opens_showing_the_folded_object(empty_scene, wavy, tmp_path):
    """The .blend held the object alone, so File ▸ Open showed an empty scene ("Library file, loading empty
    scene"); it now holds the export's scene, with the object in it and the baked frame range."""
    mesh, frames = wavy
    path = export.export_folded_file(tmp_path / "w.blend", mesh, frames, name="Wavy", frame_numbers=[5, 10, 15])
    with bpy.data.libraries.load(str(path), link=True) as (data_from, data_to):
        data_to.scenes = list(data_from.scenes)
    try:
        assert len(data_to.scenes) == 1
        scene = data_to.scenes[0]
        assert [ob.name for ob in scene.objects] == ["Wavy"]
        assert (scene.frame_start, scene.frame_end) == (5, 15)
    finally:
        for lib in list(bpy.data.libraries):
            bpy.data.libraries.remove(lib)


def test_fold_angles_past_flat_keep_their_sign_through_the_frames(wavy):
    """The geometry gives angles in (−180°, 180°]: a valley driven past flat reads −161°. Followed from the flat
    sheet through the frames (or from the solver's own angles) it stays 199°, which a FOLD file writes as 180°;
    the add-on's FOLD export wrote −161° (the command line, from the solver, 180°)."""
    from curved_fold.core.metrics import measures

    mesh, _ = wavy
    inner = np.flatnonzero(np.isfinite(measures.fold_angles(mesh, mesh.vertices_3d)))
    e = inner[0]
    t1, t2 = (
        int(t)
        for t in np.flatnonzero(
            np.any(np.isin(mesh.triangles, mesh.edges[e]), axis=1)
            & (np.sum(np.isin(mesh.triangles, mesh.edges[e]), axis=1) == 2)
        )
    )
    a, b = mesh.edges[e]
    far = [int(v) for v in mesh.triangles[t2] if v not in (a, b)][0]
    flat = mesh.vertices_3d
    axis = (flat[b] - flat[a]) / np.linalg.norm(flat[b] - flat[a])
    frames = []
    for deg in (60.0, 120.0, 170.0, 199.0):  # turn the far corner of the second triangle about the edge
        th = np.radians(deg)
        r = flat[far] - flat[a]
        turned = r * np.cos(th) + np.cross(axis, r) * np.sin(th) + axis * (axis @ r) * (1 - np.cos(th))
        p = flat.copy()
        p[far] = flat[a] + turned
        frames.append(p)
    wrapped = measures.fold_angles(mesh, frames[-1])[e]
    followed = [a_[e] for a_ in measures.unwrapped_fold_angles(mesh, frames)]
    assert abs(abs(wrapped) - 161.0) < 1e-6 and abs(abs(followed[-1]) - 199.0) < 1e-6
    assert np.sign(followed[-1]) == np.sign(followed[0])  # the same side as it started folding
    start = np.zeros(len(mesh.edges))
    start[e] = followed[-1]
    assert measures.unwrapped_fold_angles(mesh, frames[-1:], start)[0][e] == pytest.approx(followed[-1])


def test_svg_export_keeps_cut_role_and_reimports(empty_scene, tmp_path):
    src = tmp_path / "slit.svg"
    src.write_text(SLIT_SVG)
    pattern = read_pattern(src)
    mesh = fold_pattern(pattern).mesh
    assert "C" not in mesh.assignments.tolist()  # the mesh stores the slit as border edges
    out = export.write_pattern_svg(tmp_path / "cp.svg", mesh)
    assert 'stroke="#00ff00"' in out.read_text()
    back = read_pattern(out)
    for a in "BMVC":
        assert back.count(a) == pattern.count(a), (a, back.count(a), pattern.count(a))
    assert not any("border" in w and "closed" in w for w in back.warnings)


def test_svg_export_reads_back_as_the_same_pattern_and_fold(empty_scene, tmp_path):
    """Our crease-pattern SVG, read back, is the pattern we wrote and folds the same: its vertices to the last bit
    (six significant digits moved them by up to 1e-3 mm, and Rotating_Star then folded into another state: 52
    iterations, warp up to 56° instead of 24 and 31°), its polylines read as the curves they are (the ruling swaps
    score them; before, the fold got the plain constrained Delaunay mesh)."""
    pattern = read_pattern(FIXTURES / "Rotating_Star.svg")
    run = fold_pattern(pattern)
    back = read_pattern(export.write_pattern_svg(tmp_path / "star.svg", run.mesh))
    a = pattern.vertices - pattern.vertices.min(axis=0)
    b = back.vertices - back.vertices.min(axis=0)
    assert len(a) == len(b)
    assert np.max(np.min(np.linalg.norm(a[:, None] - b[None], axis=2), axis=1)) < 1e-9
    assert back.edge_from_curve.sum() == pattern.edge_from_curve.sum() > 0
    again = fold_pattern(back)
    assert again.result.converged and again.result.iterations == run.result.iterations
    assert again.result.energy == pytest.approx(run.result.energy, rel=1e-9)
    assert again.report["warp_max_deg"] == pytest.approx(run.report["warp_max_deg"], rel=1e-6)


def test_svg_export_of_a_finely_sampled_curve_reads_back_vertex_for_vertex(empty_scene, tmp_path):
    """A helper's case: a wavy crease whose curvature samples it finer than a quarter of the interval. Our export of
    it, read back, was thinned like a polyline drawn far too finely (nine samples gone: 209 → 191 faces, 29 → 27
    iterations); the export marks its polylines (``data-curved-fold="sampled"``) and they read back as written."""
    run = fold_pattern(read_pattern(DATA / "wavy_crease.svg"))
    out = export.write_pattern_svg(tmp_path / "back.svg", run.mesh)
    assert 'data-curved-fold="sampled"' in out.read_text()
    again = fold_pattern(read_pattern(out))
    assert again.mesh.n_vertices == run.mesh.n_vertices and again.mesh.n_faces == run.mesh.n_faces
    a = run.mesh.vertices - run.mesh.vertices.min(axis=0)
    b = again.mesh.vertices - again.mesh.vertices.min(axis=0)
    assert np.max(np.min(np.linalg.norm(a[:, None] - b[None], axis=2), axis=1)) < 1e-9
    assert again.result.iterations == run.result.iterations
    assert again.result.energy == pytest.approx(run.result.energy, rel=1e-9)


def test_svg_export_border_chords_longer_than_the_interval_read_back_as_written(empty_scene, tmp_path):
    """A designer session's Blender fold (a Bézier circle border, a valley ending at 41°): where the crease meets
    the border, a border sample beside the junction is dropped and the chord there is 10.001 mm at a 10 mm
    interval. Its export read back split that chord again (158 → 160 faces). Our polylines' pieces are the meshed
    pattern's and are not split again; the same ring drawn by hand still is."""
    ring = [(100.0 * math.cos(t), 100.0 * math.sin(t)) for t in np.linspace(0.0, 2 * math.pi, 64)]
    ring[-1] = ring[0]
    points = " ".join(f"{x!r},{-y!r}" for x, y in ring)
    interval = 0.9999 * math.dist(ring[0], ring[1])  # every chord of the ring a hair longer than the interval
    body = f'stroke="#000000" fill="none" points="{points}"/></svg>'
    head = '<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="200mm" viewBox="-100 -100 200 200">'
    (tmp_path / "ours.svg").write_text(head + '<polyline data-curved-fold="sampled" ' + body)
    (tmp_path / "drawn.svg").write_text(head + "<polyline " + body)
    ours, drawn = (read_pattern(tmp_path / name, interval=interval) for name in ("ours.svg", "drawn.svg"))
    assert ours.n_edges == len(ring) - 1
    assert drawn.n_edges > len(ring) - 1


def test_svg_cutter_layout_has_cut_and_score_layers(empty_scene, tmp_path):
    import xml.etree.ElementTree as ET

    src = tmp_path / "slit.svg"
    src.write_text(SLIT_SVG)
    pattern = read_pattern(src)
    mesh = fold_pattern(pattern).mesh
    out = export.write_pattern_svg(tmp_path / "cut.svg", mesh, layout="cutter", cut_width=0.01, score_width=0.3)
    ns = {"s": "http://www.w3.org/2000/svg"}
    root = ET.parse(out).getroot()
    layers = {g.get("id"): g.findall("s:polyline", ns) for g in root.findall("s:g", ns)}
    assert set(layers) == {"cut", "score"}
    assert {p.get("stroke") for p in layers["cut"]} == {"#000000", "#00ff00"}
    assert {p.get("stroke") for p in layers["score"]} == {"#ff0000", "#0000ff"}
    assert {p.get("stroke-width") for p in layers["cut"]} == {"0.01"}
    assert {p.get("stroke-width") for p in layers["score"]} == {"0.3"}
    assert not any(p.get("opacity") for ps in layers.values() for p in ps)
    back = read_pattern(out)
    assert [back.count(a) for a in "BMVC"] == [pattern.count(a) for a in "BMVC"]
    with pytest.raises(ValueError, match="SVG layout 'laser'"):
        export.write_pattern_svg(tmp_path / "x.svg", mesh, layout="laser")


def _validator() -> list[str] | None:
    """The Khronos glTF validator's command: ``GLTF_VALIDATOR`` or an npm ``gltf-validator`` install found in
    ``tools/node_modules`` or the global npm root (tools/setup.sh installs it)."""
    node = shutil.which("node")
    if node is None:
        return None
    roots = [os.environ.get("GLTF_VALIDATOR_ROOT", ""), str(REPO / "tools" / "node_modules")]
    npm = shutil.which("npm")
    if npm:
        with_root = subprocess.run([npm, "root", "-g"], capture_output=True, text=True, timeout=60)
        roots.append(with_root.stdout.strip())
    for root in filter(None, roots):
        if (Path(root) / "gltf-validator" / "package.json").is_file():
            return [node, "-e", VALIDATE_JS, str(Path(root) / "gltf-validator")]
    return None


VALIDATE_JS = """
const [validatorPath, file] = process.argv.slice(1);
const validator = require(validatorPath);
const fs = require('fs');
validator.validateBytes(new Uint8Array(fs.readFileSync(file)))
  .then((r) => { console.log(JSON.stringify(r.issues)); })
  .catch((e) => { console.error(String(e)); process.exit(1); });
"""


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_khronos_gltf_validator_accepts_our_glb(empty_scene, wavy, tmp_path, suffix):
    cmd = _validator()
    if cmd is None:
        pytest.skip("node or the npm package gltf-validator is not installed (tools/setup.sh installs both)")
    mesh, frames = wavy
    path = export.export_folded_file(tmp_path / f"w{suffix}", mesh, frames)
    proc = subprocess.run([*cmd, str(path)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    issues = json.loads(proc.stdout)
    assert issues["numErrors"] == 0, issues["messages"][:5]
    assert issues["numWarnings"] == 0, issues["messages"][:5]


def test_gltf_is_the_glb_in_one_text_file_and_reads_back_with_its_animation(empty_scene, wavy, tmp_path):
    """``.gltf`` was refused on the command line and not offered by Export Mesh (Blender writes it as a .gltf and a
    .bin, two files no write can replace all or nothing). It is now the GLB's JSON with its binary chunk embedded as a
    data URI: one file, the same accessors and bytes, and Blender's importer reads back the mesh and one shape key
    per frame."""
    from curved_fold.core.io.gltf import DATA_URI

    mesh, frames = wavy
    glb = export.export_folded_file(tmp_path / "w.glb", mesh, frames)
    gltf = export.export_folded_file(tmp_path / "w.gltf", mesh, frames)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.glb", "w.gltf"]  # no .bin beside it
    doc, blob = read_glb(glb)
    text = json.loads(gltf.read_text(encoding="utf-8"))
    uri = text["buffers"][0].pop("uri")
    assert uri.startswith(DATA_URI)
    assert base64.b64decode(uri[len(DATA_URI) :]) == blob[: doc["buffers"][0]["byteLength"]]
    assert text == doc
    bpy.ops.wm.read_homefile(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=str(gltf))
    (ob,) = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    assert len(ob.data.polygons) == len(mesh.triangles)
    assert len(ob.data.shape_keys.key_blocks) == 1 + len(frames)


@pytest.mark.parametrize("suffix", [".glb", ".gltf", ".obj", ".stl", ".blend"])
def test_blender_exporter_failing_midway_keeps_the_old_file(empty_scene, wavy, tmp_path, monkeypatch, suffix):
    """Every Blender exporter writes to a temporary file that replaces the target only when whole (the Export
    operator and the command line both go through ``export_folded_file``): a writer that dies half-way, or one that
    silently leaves a cut file (Blender's OBJ writer ignores write errors), leaves the old file byte for byte."""
    mesh, frames = wavy
    path = tmp_path / f"w{suffix}"
    path.write_bytes(b"the user's previous file")
    real = export._run_exporter

    def half_then_raise(tmp, *args, **kwargs):
        real(tmp, *args, **kwargs)
        Path(tmp).write_bytes(Path(tmp).read_bytes()[:100])
        raise RuntimeError("Error: disk full")

    def cut_silently(tmp, *args, **kwargs):
        real(tmp, *args, **kwargs)
        data = Path(tmp).read_bytes()
        Path(tmp).write_bytes(data[: len(data) // 2])

    for writer, error in ((half_then_raise, RuntimeError), (cut_silently, OSError)):
        monkeypatch.setattr(export, "_run_exporter", writer)
        with pytest.raises(error):
            export.export_folded_file(path, mesh, frames[-1])
        assert path.read_bytes() == b"the user's previous file"
        assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]
    monkeypatch.setattr(export, "_run_exporter", real)
    export.export_folded_file(path, mesh, frames[-1])
    assert path.stat().st_size > 1000
