"""The Blender workflow as a designer meets it, through ``bpy.ops`` with the extension installed from its zip.

Import groups a pattern into a handful of objects and keeps its exact strokes, so folding the imported curves gives
the command line's mesh and figures; roles keep their angles; Override Crease Angles applies to every crease; Live
follows every fold setting; folded meshes are named after the pattern and placed beside the last one; every
operator is in the Object ▸ Curved Fold menu; .svg/.fold drag-and-drop; Blender's conventions for properties.
"""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path

import bpy
import numpy as np
import pytest

from .conftest import FIXTURES, REPO, ext_module

EXAMPLES = sorted((REPO / "examples").glob("*.svg"))
REAL = sorted((FIXTURES / "origami-simulator").glob("*.svg"))
BIG = {"Carved_Cylinder.svg", "CircularPleat-antiFacet.svg", "Rotating_Star.svg", "Treble_Clef.svg", "huffmanTower.svg"}
"""Fixtures whose fold takes seconds: their full add-on-vs-command-line fold runs as ``slow``."""

PATTERNS = [pytest.param(p, id=p.name) for p in EXAMPLES + REAL]
FOLDS = [pytest.param(p, id=p.name, marks=[pytest.mark.slow] if p.name in BIG else []) for p in EXAMPLES + REAL]


def import_file(path: Path) -> list[bpy.types.Object]:
    assert bpy.ops.curved_fold.import_pattern(filepath=str(path)) == {"FINISHED"}
    return list(bpy.data.collections[path.stem].objects)


def fold_fixture(name: str) -> bpy.types.Object:
    """Import an Origami Simulator fixture and Fold it (at 100 %); the folded object."""
    path = FIXTURES / "origami-simulator" / name
    import_file(path)
    assert bpy.ops.curved_fold.fold(collection=path.stem) == {"FINISHED"}
    return bpy.context.active_object


def expected_groups(extension, path: Path) -> set[tuple[str, float | None]]:
    """(assignment, fold angle) of the file's strokes: the objects an import should make, one per pair."""
    curves, _ = ext_module(extension, "core.io.reader").read_curves(path)
    return {(c.assignment, c.fold_angle if c.assignment in "MVF" else None) for c in curves}


@pytest.mark.parametrize("path", PATTERNS)
def test_import_makes_one_object_per_role_and_angle(extension, clean_scene, path):
    curves, _ = ext_module(extension, "core.io.reader").read_curves(path)
    objects = import_file(path)
    assert len(objects) == len(expected_groups(extension, path))
    assert len(objects) <= 8  # CircularPleat-antiFacet: 4 objects, not 3,200
    assert sum(len(ob.data.splines) for ob in objects) <= len(curves)
    for ob in objects:
        assert ob.curved_fold.role != "NONE"


@pytest.mark.parametrize("path", PATTERNS)
def test_imported_curves_give_the_command_line_pattern_and_mesh(extension, clean_scene, path):
    """Unedited imports discretise to the very pattern the command line makes of the file: same vertices, edges and
    angles, hence the same triangles."""
    reader = ext_module(extension, "core.io.reader")
    folding = ext_module(extension, "scene.folding")
    build = ext_module(extension, "core.mesh.build")
    objects = import_file(path)
    ours = folding.pattern_from_objects(objects)
    theirs = reader.read_pattern(path)
    np.testing.assert_array_equal(ours.vertices, theirs.vertices)
    np.testing.assert_array_equal(ours.edges, theirs.edges)
    np.testing.assert_array_equal(ours.assignments, theirs.assignments)
    np.testing.assert_array_equal(ours.fold_angles, theirs.fold_angles)
    np.testing.assert_array_equal(ours.edge_from_curve, theirs.edge_from_curve)
    a, b = build.build_mesh(ours), build.build_mesh(theirs)
    np.testing.assert_array_equal(a.triangles, b.triangles)


def test_our_svg_export_imported_folds_like_the_command_line(extension, clean_scene, tmp_path):
    """Our SVG export of a curve sampled finer than a quarter of the interval (``tests/data/wavy_crease.svg``,
    folded), imported: its polylines carry the export's mark through the import's exact strokes, so Blender keeps
    them as written like the command line does, and both make the mesh the file was written from."""
    reader = ext_module(extension, "core.io.reader")
    pipeline = ext_module(extension, "core.pipeline")
    folding = ext_module(extension, "scene.folding")
    export = ext_module(extension, "scene.export")
    run = pipeline.fold_pattern(reader.read_pattern(REPO / "tests" / "data" / "wavy_crease.svg"))
    path = export.write_pattern_svg(tmp_path / "wavy_back.svg", run.mesh)
    ours = folding.pattern_from_objects(import_file(path))
    theirs = reader.read_pattern(path)
    np.testing.assert_array_equal(ours.vertices, theirs.vertices)
    np.testing.assert_array_equal(ours.edges, theirs.edges)
    assert len(ours.vertices) == run.mesh.n_vertices


def test_the_command_line_writes_the_flat_svg_that_export_svg_writes(extension, clean_scene, tmp_path):
    """``fold X --out x.svg`` writes the fold's flat crease pattern, byte for byte what Blender's Export SVG writes
    of the same file's fold (it was Blender-only: "unknown output type '.svg'", a parity review session), but for
    the ``data-source`` notes, which name where each stroke came from (Blender names the curve object too)."""
    import re

    from curved_fold.cli import main

    path = FIXTURES / "origami-simulator" / "Treble_Clef.svg"
    assert main(["fold", str(path), "--out", str(tmp_path / "cli.svg"), "-q"]) == 0
    import_file(path)
    assert bpy.ops.curved_fold.fold(collection=path.stem) == {"FINISHED"}
    assert bpy.ops.curved_fold.export_pattern_svg(filepath=str(tmp_path / "ui.svg")) == {"FINISHED"}
    cli, ui = ((tmp_path / name).read_text() for name in ("cli.svg", "ui.svg"))
    assert cli.count("<polyline") == ui.count("<polyline") >= 2  # the border and the valley chains
    assert re.sub(r' data-source="[^"]*"', "", cli) == re.sub(r' data-source="[^"]*"', "", ui)


def test_the_fold_object_keeps_its_pattern_to_the_last_bit(extension, clean_scene):
    """Blender's attributes are single precision; the fold object keeps the flat positions and the target fold angles
    as doubles too, so what reads it back (Re-fold, Bake, Export SVG) has the mesh the fold was made of. From the
    float32 copy a helper's ten-ring pleat re-folded in 133 iterations instead of the Fold's 132, and its exported
    SVG had 880 of 928 vertices moved by up to 4e-6 mm. A copy that no longer rounds to the attributes is not used."""
    reader = ext_module(extension, "core.io.reader")
    pipeline = ext_module(extension, "core.pipeline")
    mesh_object = ext_module(extension, "scene.mesh_object")
    path = FIXTURES / "origami-simulator" / "Treble_Clef.svg"
    import_file(path)
    assert bpy.ops.curved_fold.fold(collection=path.stem) == {"FINISHED"}
    ob = bpy.context.active_object
    stored = mesh_object.read_fold_mesh(ob)
    made = pipeline.fold_pattern(reader.read_pattern(path)).mesh
    assert not np.array_equal(made.vertices, made.vertices.astype(np.float32))  # float32 would not do
    np.testing.assert_array_equal(stored.vertices, made.vertices)
    made_angles = dict(zip(map(tuple, made.edges.tolist()), made.fold_angles.tolist(), strict=True))
    np.testing.assert_array_equal(stored.fold_angles, [made_angles[tuple(e)] for e in stored.edges.tolist()])
    flat = ob.data[mesh_object.EXACT_FLAT_KEY]
    ob.data[mesh_object.EXACT_FLAT_KEY] = [x + 1.0 for x in flat.to_list()]  # e.g. the elements sorted since
    np.testing.assert_array_equal(
        mesh_object.read_fold_mesh(ob).vertices, made.vertices.astype(np.float32).astype(np.float64)
    )


@pytest.mark.parametrize("unit_scale", [1.0, 0.001])
def test_refold_of_an_unedited_fold_is_the_fold(extension, clean_scene, unit_scale):
    """Re-fold right after Fold solves the same model from the same mesh, so it gives the same fold, to the bit. It
    read the edges back in Blender's order (the hinges summed in another order) and the stiffnesses as single
    precision properties (0.699999988 for 0.7): a reviewer's wavy crease re-folded in 25 iterations instead of 24,
    and a pattern stopping at the round-off floor in 176 instead of 159, a vertex 3 mm away."""
    fold_settings = ext_module(extension, "scene.fold_settings")
    bpy.context.scene.unit_settings.scale_length = unit_scale
    path = REPO / "tests" / "data" / "wavy_crease.svg"
    import_file(path)
    assert bpy.ops.curved_fold.fold(collection=path.stem) == {"FINISHED"}
    ob = bpy.context.active_object
    props = ob.curved_fold_mesh
    assert fold_settings.settings_dict(props)["crease_stiffness"] == 0.7
    folded = (props.last_iterations, props.last_strain_mean, np.array([v.co for v in ob.data.vertices]))
    for rebuild in ("AUTO", "RESOLVE", "REBUILD"):
        assert bpy.ops.curved_fold.refold(rebuild=rebuild) == {"FINISHED"}
        assert (props.last_iterations, props.last_strain_mean) == folded[:2], rebuild
        np.testing.assert_array_equal(np.array([v.co for v in ob.data.vertices]), folded[2])


def test_imports_at_a_millimetre_unit_scale_give_the_command_line_pattern(extension, clean_scene):
    """With the scene's Unit Scale at 0.001 (1 Blender unit = 1 mm), single precision holds 0.0010000000474974513:
    read as is, every imported point moved by up to 9.5e-6 mm and a pattern that stops at the round-off floor folded
    in 113 iterations instead of the command line's 159. The scale is read as the decimal shown."""
    reader = ext_module(extension, "core.io.reader")
    folding = ext_module(extension, "scene.folding")
    bpy.context.scene.unit_settings.scale_length = 0.001
    path = FIXTURES / "origami-simulator" / "Treble_Clef.svg"
    ours = folding.pattern_from_objects(import_file(path))
    np.testing.assert_array_equal(ours.vertices, reader.read_pattern(path).vertices)


@pytest.mark.parametrize("path", FOLDS)
def test_fold_operator_figures_equal_the_command_line(extension, clean_scene, path):
    reader = ext_module(extension, "core.io.reader")
    pipeline = ext_module(extension, "core.pipeline")
    import_file(path)
    assert bpy.ops.curved_fold.fold(collection=path.stem) == {"FINISHED"}
    props = bpy.context.active_object.curved_fold_mesh
    report = pipeline.fold_pattern(reader.read_pattern(path)).report
    assert (props.last_faces, props.last_vertices) == (report["faces"], report["vertices"])
    assert props.last_cpu_ms > 0  # the Last Run panel gives the solver's CPU time beside its wall time
    for ours, key in (
        (props.last_strain_mean, "strain_mean_pct"),
        (props.last_strain_max, "strain_max_pct"),
        (props.last_warp_mean, "warp_mean_deg"),
        (props.last_fold_error, "fold_angle_error_mean_deg"),
    ):
        theirs = report[key] if np.isfinite(report[key]) else 0.0
        assert ours == pytest.approx(theirs, rel=1e-5, abs=1e-9), key  # the properties are float32


@pytest.mark.parametrize("name", ["cannot_fold", "curved_pleats", "huffmanTower"])
def test_fold_file_import_folds_like_the_command_line(extension, clean_scene, tmp_path, name):
    """A FOLD file is folded as it is by the command line (no re-discretisation, its curve flags kept); its unedited
    import folds to the same mesh and figures. An edited one is discretised from the curves as drawn, its polylines
    read as curves again (``flattened_curves``)."""
    reader = ext_module(extension, "core.io.reader")
    fold_io = ext_module(extension, "core.io.fold")
    pipeline = ext_module(extension, "core.pipeline")
    folding = ext_module(extension, "scene.folding")
    source = next(p for p in EXAMPLES + REAL if p.stem == name)
    path = tmp_path / f"{name}.fold"
    fold_io.write_pattern_fold(path, reader.read_pattern(source))
    objects = import_file(path)
    theirs = reader.read_pattern(path)
    ours = folding.pattern_from_objects(objects)
    for key in ("vertices", "edges", "assignments", "fold_angles", "edge_from_curve", "edge_polyline"):
        np.testing.assert_array_equal(getattr(ours, key), getattr(theirs, key), err_msg=key)
    assert bpy.ops.curved_fold.fold(collection=path.stem) == {"FINISHED"}
    props = bpy.context.active_object.curved_fold_mesh
    report = pipeline.fold_pattern(theirs).report
    assert props.last_faces == report["faces"]
    assert props.last_warp_mean == pytest.approx(report["warp_mean_deg"], rel=1e-5)
    assert props.last_strain_mean == pytest.approx(report["strain_mean_pct"], rel=1e-5)
    # Edited (one point moved): discretised from the curves as drawn, no longer the stored pattern.
    spline = objects[0].data.splines[0]
    points = spline.points if spline.type == "POLY" else spline.bezier_points
    points[0].co.x += 1e-4
    edited = folding.pattern_from_objects(objects)
    moved = edited.vertices.shape != theirs.vertices.shape or not np.array_equal(edited.vertices, theirs.vertices)
    assert moved
    # its polylines still read as the curves they are (flattened curves), the straight pattern's as straight
    assert edited.edge_from_curve.any() == theirs.edge_from_curve.any() == (name != "huffmanTower")


def test_another_tools_fold_file_is_sampled_at_the_fold_operators_interval(extension, clean_scene, tmp_path):
    """Another tool's FOLD file (a sine crease as a 201-point polyline) is sampled at the interval the fold asks for,
    as ``--interval`` samples it on the command line; the import kept it sampled at the automatic interval, so the
    Fold panel's Interval changed nothing (a guide note, fifteenth pass)."""
    reader = ext_module(extension, "core.io.reader")
    pipeline = ext_module(extension, "core.pipeline")
    bpy.context.scene.unit_settings.scale_length = 0.001  # 1 Blender unit = 1 mm: the interval is exact
    u = np.linspace(0.0, 1.0, 201)
    coords = [[0.0, 0.0], [100.0, 0.0], [100.0, 100.0], [0.0, 100.0]]
    coords += [[50.0 + 10.0 * math.sin(2 * math.pi * t), 100.0 * t] for t in u[1:-1]]
    coords[4:4] = [[50.0, 0.0], [50.0, 100.0]]  # the sine's ends, on the border
    sine = [4, *range(6, len(coords)), 5]
    edges = [[0, 4], [4, 1], [1, 2], [2, 5], [5, 3], [3, 0]] + [
        [a, b] for a, b in zip(sine[:-1], sine[1:], strict=True)
    ]
    assign = ["B"] * 6 + ["V"] * (len(sine) - 1)
    doc = {"file_spec": 1.1, "frame_unit": "mm", "vertices_coords": coords, "edges_vertices": edges}
    path = tmp_path / "sine.fold"
    path.write_text(json.dumps(doc | {"edges_assignment": assign, "edges_foldAngle": [0.0] * 6 + [90.0] * 200}))
    import_file(path)
    faces = {}
    for interval in (0.0, 2.0):
        assert bpy.ops.curved_fold.fold(collection="sine", interval=interval) == {"FINISHED"}
        props = bpy.context.active_object.curved_fold_mesh
        report = pipeline.fold_pattern(reader.read_pattern(path, interval=interval or None)).report
        assert (props.last_faces, props.last_vertices) == (report["faces"], report["vertices"]), interval
        assert props.last_strain_mean == pytest.approx(report["strain_mean_pct"], rel=1e-5)
        faces[interval] = props.last_faces
    assert faces[2.0] > faces[0.0]  # the automatic interval on a 100 mm sheet is 4.7 mm


def test_arcs_stay_arcs_lines_stay_lines_and_edits_win(extension, clean_scene):
    curves_mod = ext_module(extension, "scene.curves")
    path = REPO / "examples" / "cannot_fold.svg"
    objects = import_file(path)
    kinds = {s.kind for c in curves_mod.curves_from_objects(objects) for s in c.segments}
    assert kinds == {"arc", "line"}
    # Moving (and mirroring) the objects keeps the exact arcs, moved with them.
    before = curves_mod.curves_from_objects(objects)
    for ob in objects:
        ob.location = (0.125, 0.0625, 0.0)  # exact in float32
        ob.scale = (-1.0, 1.0, 1.0)
    bpy.context.view_layer.update()
    moved = curves_mod.curves_from_objects(objects)
    assert [s.kind for c in moved for s in c.segments] == [s.kind for c in before for s in c.segments]
    t = np.linspace(0.0, 1.0, 9)
    for c0, c1 in zip(before, moved, strict=True):
        for s0, s1 in zip(c0.segments, c1.segments, strict=True):
            p0 = s0.evaluate(t) * np.array([-1.0, 1.0]) + np.array([125.0, 62.5])  # 1 BU = 1000 mm
            np.testing.assert_allclose(s1.evaluate(t), p0, rtol=0, atol=1e-9)
    # Rotated and uniformly scaled: still the exact arcs, rotated and scaled with the objects.
    for ob in objects:
        ob.location = (0.0, 0.0, 0.0)
        ob.scale = (2.0, 2.0, 2.0)
        ob.rotation_euler = (0.0, 0.0, 0.5)
    bpy.context.view_layer.update()
    turned = curves_mod.curves_from_objects(objects)
    c, s_ = math.cos(0.5), math.sin(0.5)
    rot = 2.0 * np.array([[c, -s_], [s_, c]])
    assert [s.kind for c1 in turned for s in c1.segments] == [s.kind for c0 in before for s in c0.segments]
    for c0, c1 in zip(before, turned, strict=True):
        for s0, s1 in zip(c0.segments, c1.segments, strict=True):
            np.testing.assert_allclose(s1.evaluate(t), s0.evaluate(t) @ rot.T, rtol=0, atol=1e-4)  # float32 matrix
    for ob in objects:
        ob.scale = (1.0, 1.0, 1.0)
        ob.rotation_euler = (0.0, 0.0, 0.0)
    bpy.context.view_layer.update()
    # An edited spline is read as drawn (Bézier pieces); the others keep their exact strokes.
    mountain = next(ob for ob in objects if ob.curved_fold.role == "MOUNTAIN")
    bp = next(s for s in mountain.data.splines if s.type == "BEZIER").bezier_points[0]
    bp.handle_right.y += 0.005
    edited = curves_mod.curves_from_objects(objects)
    kinds = [{s.kind for s in c.segments} for c in edited if c.assignment == "M"]
    assert {"cubic"} in kinds and any("arc" in k for k in kinds)


def test_polylines_become_poly_splines(extension, clean_scene):
    objects = import_file(FIXTURES / "origami-simulator" / "curvedPleatSimple.svg")  # straight lines only
    assert {s.type for ob in objects for s in ob.data.splines} == {"POLY"}  # lines stay lines


def test_role_change_keeps_the_angle_unless_one_is_given(extension, clean_scene):
    objects = import_file(REPO / "examples" / "concentric_arcs.svg")
    valley = next(ob for ob in objects if ob.curved_fold.role == "VALLEY")
    assert math.degrees(valley.curved_fold.fold_angle) == pytest.approx(108.0, abs=1e-4)
    for ob in bpy.context.selected_objects:
        ob.select_set(False)
    valley.select_set(True)
    assert bpy.ops.curved_fold.set_crease_role(role="MOUNTAIN") == {"FINISHED"}
    assert valley.curved_fold.role == "MOUNTAIN"
    assert math.degrees(valley.curved_fold.fold_angle) == pytest.approx(108.0, abs=1e-4)
    curve = ext_module(extension, "scene.curves").curves_from_objects([valley])[0]
    assert curve.fold_angle == pytest.approx(-108.0, abs=1e-4)
    assert bpy.ops.curved_fold.set_crease_role(role="VALLEY", use_fold_angle=True, fold_angle=math.pi / 2) == {
        "FINISHED"
    }
    assert valley.curved_fold.fold_angle == pytest.approx(math.pi / 2)
    assert bpy.ops.curved_fold.set_crease_role(role="MOUNTAIN", fold_angle=math.pi / 4) == {"FINISHED"}  # a script
    assert valley.curved_fold.fold_angle == pytest.approx(math.pi / 4)


def test_override_crease_angles_applies_to_every_crease(extension, clean_scene):
    objects = import_file(REPO / "examples" / "concentric_arcs.svg")  # creases drawn at ±108°
    creases = [ob for ob in objects if ob.curved_fold.role in {"MOUNTAIN", "VALLEY"}]
    assert all(math.degrees(ob.curved_fold.fold_angle) == pytest.approx(108.0, abs=1e-4) for ob in creases)
    result = bpy.ops.curved_fold.fold(collection="concentric_arcs", use_fold_angle=True, fold_angle=math.pi / 2)
    assert result == {"FINISHED"}
    me = bpy.context.active_object.data
    n = len(me.edges)
    target = np.empty(n, np.float32)
    me.attributes["cf_fold_angle"].data.foreach_get("value", target)
    code = np.empty(n, np.int8)
    me.attributes["cf_assignment"].data.foreach_get("value", code)
    letters = np.array(ext_module(extension, "core.pattern.model").ASSIGNMENTS)[code]
    np.testing.assert_allclose(target[letters == "V"], 90.0, atol=1e-4)
    np.testing.assert_allclose(target[letters == "M"], -90.0, atol=1e-4)
    assert (letters == "V").any() and (letters == "M").any()


def test_live_refolds_on_a_stiffness_change(extension, clean_scene):
    live = ext_module(extension, "scene.live")
    import_file(REPO / "examples" / "single_curve.svg")
    assert bpy.ops.curved_fold.fold(collection="single_curve", fold_percent=60.0) == {"FINISHED"}
    ob = bpy.context.active_object
    props = ob.curved_fold_mesh
    before = np.array([v.co[:] for v in ob.data.vertices])
    props.live = True
    live._pending.clear()
    for name in ("axial_stiffness", "panel_stiffness", "face_stiffness", "damping", "crease_stiffness"):
        live._pending.clear()
        setattr(props, name, getattr(props, name) * 0.5)
        assert ob.name in live._pending, name  # every solve setting schedules a re-fold
        setattr(props, name, getattr(props, name) * 2.0)
    live._pending.clear()
    props.crease_stiffness = 0.05  # much weaker creases against the same panels: a visibly different shape
    assert live.run_pending() == {ob.name: "ok"}
    after = np.array([v.co[:] for v in ob.data.vertices])
    assert after.shape == before.shape and np.abs(after - before).max() > 1e-4
    props.live = False


def x_extent(ob) -> tuple[float, float]:
    """World x extent (min, max) of ``ob``'s bounding box."""
    m = np.array(ob.matrix_world)
    c = np.array([tuple(v) for v in ob.bound_box]) @ m[:3, :3].T + m[:3, 3]
    return c[:, 0].min(), c[:, 0].max()


def test_folds_are_named_after_the_pattern_and_placed_beside_the_last(extension, clean_scene):
    objects = import_file(REPO / "examples" / "single_curve.svg")
    made = []
    for _ in range(2):
        for ob in bpy.context.selected_objects:
            ob.select_set(False)
        for ob in objects:
            ob.select_set(True)
        assert bpy.ops.curved_fold.fold() == {"FINISHED"}
        made.append(bpy.context.active_object)
    assert made[0].name == "single_curve Folded" and made[1].name.startswith("single_curve Folded")
    bpy.context.view_layer.update()

    curves_right = max(x_extent(ob)[1] for ob in objects)
    assert x_extent(made[0])[0] > curves_right
    assert x_extent(made[1])[0] > x_extent(made[0])[1]  # no overlap with the last fold


def test_a_fold_is_placed_clear_of_another_sheet_beside_its_curves(extension, clean_scene):
    """Two sheets drawn side by side: a fold of the first goes right of its curves, and further right past the
    second sheet when that spot is taken (it was placed on the second sheet's curves, a helper's report)."""
    first = import_file(REPO / "examples" / "single_curve.svg")
    second = import_file(REPO / "examples" / "curved_pleats.svg")
    bpy.context.view_layer.update()

    right = max(x_extent(ob)[1] for ob in first)
    shift = right + 0.05 * (right - min(x_extent(ob)[0] for ob in first)) - min(x_extent(ob)[0] for ob in second)
    for ob in second:
        ob.location.x += shift
    bpy.context.view_layer.update()
    assert bpy.ops.curved_fold.fold(collection="single_curve") == {"FINISHED"}
    bpy.context.view_layer.update()
    assert x_extent(bpy.context.active_object)[0] > max(x_extent(ob)[1] for ob in second)


def test_exported_gltf_node_keeps_the_object_name(extension, clean_scene, tmp_path):
    import_file(REPO / "examples" / "single_curve.svg")
    assert bpy.ops.curved_fold.fold(collection="single_curve") == {"FINISHED"}
    ob = bpy.context.active_object
    path = tmp_path / "out.glb"
    name = ob.name
    assert bpy.ops.curved_fold.export_folded(filepath=str(path), file_format="GLB") == {"FINISHED"}
    assert ob.name == name  # the user's object keeps its name
    data = path.read_bytes()
    length = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20 : 20 + length])
    assert ob.name in [node.get("name") for node in gltf["nodes"]]


def test_every_operator_is_in_the_object_menu_and_files_can_be_dropped(extension):
    """Every operator but the internal ones (the Cancel button of a running job's progress row) is in the menu."""
    source = Path(ext_module(extension, "operators.menus").__file__).read_text()
    operators = [
        name
        for name in dir(bpy.ops.curved_fold)
        if not name.startswith("_") and "INTERNAL" not in getattr(bpy.types, f"CURVED_FOLD_OT_{name}").bl_options
    ]
    assert operators and "cancel_job" not in operators
    for name in operators:
        assert f'"curved_fold.{name}"' in source, name
    assert "_menu" in [f.__name__ for f in bpy.types.VIEW3D_MT_object._dyn_ui_initialize()]
    handler = bpy.types.FileHandler.bl_rna_get_subclass_py("CURVED_FOLD_FH_crease_pattern")
    assert handler is not None
    assert set(handler.bl_file_extensions.split(";")) == {".svg", ".fold"}
    assert handler.bl_import_operator == "curved_fold.import_pattern"


def test_dropped_files_are_all_imported(extension, clean_scene):
    """What a drop on the viewport passes to the FileHandler's operator: a directory and file names."""
    names = ["single_curve.svg", "curved_border.svg"]
    result = bpy.ops.curved_fold.import_pattern(directory=str(REPO / "examples"), files=[{"name": n} for n in names])
    assert result == {"FINISHED"}
    assert {"single_curve", "curved_border"} <= set(bpy.data.collections.keys())
    assert {ob.name for ob in bpy.context.selected_objects} == {
        ob.name for n in names for ob in bpy.data.collections[Path(n).stem].objects
    }


def _groups():
    yield bpy.types.Object.bl_rna.properties["curved_fold"].fixed_type
    yield bpy.types.Object.bl_rna.properties["curved_fold_mesh"].fixed_type
    for name in dir(bpy.ops.curved_fold):
        if not name.startswith("_"):
            yield getattr(bpy.ops.curved_fold, name).get_rna_type()


def test_every_property_has_a_tooltip_and_results_are_not_animatable(extension):
    missing = [
        f"{group.identifier}.{p.identifier}"
        for group in _groups()
        for p in group.properties
        if p.identifier != "rna_type" and not p.description and not p.is_hidden
    ]
    assert not missing, missing
    mesh_props = bpy.types.Object.bl_rna.properties["curved_fold_mesh"].fixed_type.properties
    for p in mesh_props:
        if p.identifier.startswith("last_") or p.identifier in {"baked_frames", "is_fold_mesh"}:
            assert not p.is_animatable, p.identifier
    assert mesh_props["fold_percent"].is_animatable


def test_enum_identifiers_are_upper_case_as_blenders(extension):
    """Every enum of ours uses Blender's identifier style (``RULING``, ``FAST``; the engine's lower-case names are
    mapped at one place, ``fold_settings.engine_id``)."""
    mixed = [
        f"{group.identifier}.{p.identifier}: {item.identifier}"
        for group in _groups()
        for p in group.properties
        if p.type == "ENUM"
        for item in p.enum_items
        if item.identifier != item.identifier.upper()
    ]
    assert not mixed, mixed
    mesh_props = bpy.types.Object.bl_rna.properties["curved_fold_mesh"].fixed_type.properties
    assert {i.identifier for i in mesh_props["mesh_type"].enum_items} == {"RULING", "CDT", "EARCUT"}


def test_show_colors_material_message(extension, clean_scene):
    import_file(REPO / "examples" / "single_curve.svg")
    assert bpy.ops.curved_fold.fold(collection="single_curve") == {"FINISHED"}
    assert bpy.ops.curved_fold.show_colours(kind="NONE") == {"FINISHED"}
    assert bpy.types.CURVED_FOLD_OT_show_colours.bl_label == "Show Fold Colors"


def test_a_warning_is_reported_once(extension):
    """``build_mesh`` starts its warnings with the pattern's; the report lists each once (it printed them twice)."""
    model = ext_module(extension, "core.pattern.model")
    discretize = ext_module(extension, "core.pattern.discretize").discretize
    pipeline = ext_module(extension, "core.pipeline")
    square = [[0.0, 0.0], [100.0, 0.0], [100.0, 100.0], [0.0, 100.0], [0.0, 0.0]]
    border = model.CreaseCurve(
        [model.CurveSegment("line", np.array([a, b])) for a, b in zip(square[:-1], square[1:], strict=True)],
        "B",
        None,
        closed=True,
    )
    crease = model.CreaseCurve([model.CurveSegment("line", np.array([[0.0, 50.0], [100.0, 50.0]]))], "V", 90.0)
    again = model.CreaseCurve([model.CurveSegment("line", np.array([[0.0, 50.0], [100.0, 50.0]]))], "M", -90.0)
    pattern = discretize([border, crease, again])
    assert pattern.warnings
    warnings = pipeline.fold_pattern(pattern).report["warnings"]
    assert len(warnings) == len(set(warnings)) and set(pattern.warnings) <= set(warnings)


@pytest.mark.slow
def test_a_bake_ends_where_fold_does_on_a_pattern_with_several_minima(extension, clean_scene):
    """CircularPleat-antiFacet at 60 % has several stable minima within 2e-5 of each other in energy (the tuck of a
    four-lobed ring at different places, 4e-2 – 1.7e-1 of the diagonal apart). Through the UI: Fold at 60 %, then a
    0 → 60 % bake over 6 frames; the bake's last frame is the Fold's minimum (the frame cache folds it along the
    natural path; the stored mesh's float32 coordinates leave it ~3e-4 of the diagonal away, in the same valley)."""
    ob = fold_fixture("CircularPleat-antiFacet.svg")
    props = ob.curved_fold_mesh
    props.fold_percent = 60.0
    assert bpy.ops.curved_fold.refold() == {"FINISHED"}
    static = mesh_positions(ob)
    last = bake_from_flat(ob, 6)
    diag = float(np.linalg.norm(np.ptp(static, axis=0)))
    assert ext_module(extension, "core.solve.solver").rigid_rms(last, static) / diag <= 1e-3


def test_a_bake_ends_where_fold_put_the_sheet(extension, clean_scene):
    """Rotating_Star through the UI: Fold at 100 %, then a 0 → 100 % bake over 20 frames. The last frame is the
    Fold's state in place, not only in shape: it sat 0.7–2.4 % of the sheet away (a rigid motion: the placement a
    damped solve reaches depends on its path), so the mesh jumped when baked and a glTF animation did not line up
    with an export of the fold. Every result now has the sheet's centre face on the table (``core.solve.pose``);
    the star's symmetry puts several faces as near its centre, and the float32 mesh chooses the pattern's."""
    ob = fold_fixture("Rotating_Star.svg")
    static = mesh_positions(ob)
    last = bake_from_flat(ob, 20)
    diag = float(np.linalg.norm(np.ptp(static, axis=0)))
    rms = float(np.sqrt(np.mean(np.sum((last - static) ** 2, axis=1))))
    assert rms <= 1e-4 * diag  # as the static fold against the last frame, here without any alignment


def bake_from_flat(ob, frames: int) -> np.ndarray:
    """Keyframe ``ob``'s Fold Percent from 0 at frame 1 to its current value at ``frames``, bake through the
    operator, and return the evaluated mesh's positions (mm) at the last frame."""
    props = ob.curved_fold_mesh
    props.keyframe_insert("fold_percent", frame=frames)
    props.fold_percent = 0.0
    props.keyframe_insert("fold_percent", frame=1)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, frames
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}
    scene.frame_set(frames)
    return mesh_positions(ob.evaluated_get(bpy.context.evaluated_depsgraph_get()))


def mesh_positions(ob) -> np.ndarray:
    """Vertex positions of ``ob``'s mesh (evaluated if given so), mm."""
    co = np.empty(3 * len(ob.data.vertices), dtype=np.float32)
    ob.data.attributes["position"].data.foreach_get("vector", co)
    return co.reshape(-1, 3).astype(np.float64) * 1000.0


def test_a_long_bake_converges_every_frame(extension, clean_scene):
    """A 0 → 100 % bake of simpleVertex over 101 frames: every frame converges. Warm frames there need up to ~20
    Newton iterations (Gauss–Newton's linear tail); capped at playback's 12, four frames were left unconverged. A bake
    gives warm frames ``WARM_MAX_ITERATIONS`` and solves a frame that still does not converge from the natural path:
    such a frame is the static fold at its percent, exactly."""
    ob = fold_fixture("simpleVertex.svg")
    props = ob.curved_fold_mesh
    props.fold_percent = 0.0
    props.keyframe_insert("fold_percent", frame=1)
    props.fold_percent = 100.0
    props.keyframe_insert("fold_percent", frame=101)
    for fc in ext_module(extension, "scene.bake")._fcurves(ob):
        for key in fc.keyframe_points:
            key.interpolation = "LINEAR"
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 101
    assert bpy.ops.curved_fold.bake() == {"FINISHED"}
    cache = ext_module(extension, "scene.timeline").cache_for(ob)
    assert sorted(cache.frames) == list(range(1, 102))
    assert all(cache.frames[f].converged for f in cache.frames)
    solver_mod = ext_module(extension, "core.solve.solver")
    warm_startable = ext_module(extension, "core.solve.path").warm_startable
    settings = cache.solver(props).settings
    fell_back = 0
    for f in range(2, 102):
        entry, previous = cache.frames[f], cache.frames[f - 1]
        if warm_startable(previous.percent, entry.percent, settings.continuation_step) and entry.iterations > 12:
            static = solver_mod.Solver(cache.mesh, settings).solve(entry.percent).positions
            fell_back += np.array_equal(entry.positions, static)
    assert fell_back >= 1


def test_a_new_unit_scale_keeps_the_fold_the_size_of_its_curves(extension, clean_scene):
    """Fold at Unit Scale 1, switch the scene to Unit Scale 0.001 (1 BU = 1 mm): the curves keep their size in
    Blender units, so Re-solve, Bake and playback must too. The flat pattern is stored in the millimetres of the
    fold's unit scale and was read back in the new one: a helper's 100 mm sheet came back 1000× larger than its
    curves, and the notice blamed the curves ("source curves changed"), which were not touched."""
    ob = fold_fixture("simpleVertex.svg")
    state = ext_module(extension, "scene.source_state")
    folded = mesh_positions(ob)
    scene = bpy.context.scene
    scene.unit_settings.scale_length = 0.001
    bpy.context.view_layer.update()
    assert not state.sources_changed(ob, scene)
    assert bpy.ops.curved_fold.refold(rebuild="RESOLVE") == {"FINISHED"}
    assert np.allclose(mesh_positions(ob), folded, atol=1e-4 * np.ptp(folded, axis=0).max())
    baked = bake_from_flat(ob, 5)
    assert np.allclose(baked, folded, atol=1e-3 * np.ptp(folded, axis=0).max())
    scene.frame_set(3)  # playback between the keys: a shape between flat and folded, the sheet's size
    mid = mesh_positions(ob.evaluated_get(bpy.context.evaluated_depsgraph_get()))
    assert 0.5 < np.ptp(mid, axis=0)[:2].max() / np.ptp(folded, axis=0)[:2].max() < 2.0


def test_interval_and_tolerance_sliders_do_not_stop_at_a_fixed_length(extension):
    """Their slider limits were 0.05 and 0.005 Blender units: 50 mm at Unit Scale 1, but 0.05 mm at Unit Scale 0.001,
    far below the automatic 7 mm there (a helper's report). Lengths in Blender units cannot have one limit for every
    scale, so they have none (as the Fold operator's own fields)."""
    rna = bpy.types.Object.bl_rna.properties["curved_fold_mesh"].fixed_type.properties
    for name in ("interval", "tolerance"):
        assert rna[name].soft_max >= 1e6, (name, rna[name].soft_max)


def test_deleting_a_folded_mesh_deletes_its_crease_curves(extension, clean_scene):
    """Object ▸ Delete on a folded mesh: its red/blue crease curves (children that cannot be selected) go with it.
    Blender keeps a deleted object's children, unparented: they stayed in the viewport, folded in mid-air, and could
    not be clicked to delete them (a helper's report). The depsgraph handler schedules their removal on a timer
    (timers do not fire headless: the test runs the timer's call itself); removing them inside the handler freed IDs
    that the update's list still named."""
    orphans = ext_module(extension, "scene.crease_orphans")
    ob = fold_fixture("curvedPleatSimple.svg")
    creases = [c.name for c in ob.children if "cf_crease_role" in c]
    assert creases
    for other in bpy.context.selected_objects:
        other.select_set(False)
    ob.select_set(True)
    bpy.context.view_layer.objects.active = ob
    assert bpy.ops.object.delete() == {"FINISHED"}
    bpy.context.view_layer.update()
    assert bpy.app.timers.is_registered(orphans._removal)
    assert all(name in bpy.data.objects for name in creases)  # nothing removed inside the depsgraph update
    orphans._removal()
    bpy.app.timers.unregister(orphans._removal)
    assert not any(name in bpy.data.objects for name in creases)
    assert not orphans.orphaned_crease_curves()


def test_hidden_crease_curves_are_left_out_of_a_collection_fold_through_every_door(extension, clean_scene, tmp_path):
    """A pattern collection keeps an old crease hidden (H), one disabled in viewports and one in a sub-collection
    excluded from the view layer (a designer session). A fold of the collection folded all three (303 faces against
    151 for what the viewport shows), the command line folded the hidden and disabled ones; now every door folds
    what the viewport shows, with a warning naming the curves left out."""
    from .test_operators import make_curve

    curves_mod = ext_module(extension, "scene.curves")
    reader = ext_module(extension, "core.io.reader")
    pipeline = ext_module(extension, "core.pipeline")
    pattern = bpy.data.collections.new("Pattern")
    clean_scene.collection.children.link(pattern)
    old = bpy.data.collections.new("Old")
    pattern.children.link(old)
    corners = [(0, 0), (150, 0), (150, 150), (0, 150)]
    border = [np.array([corners[i], corners[i], corners[(i + 1) % 4], corners[(i + 1) % 4]], float) for i in range(4)]
    make_curve("Border", border, "BORDER", closed=True, collection=pattern)

    def crease(name, pts, role, collection):
        return make_curve(name, [np.array(pts, float)], role, 108.0, collection=collection)

    valley = crease("Valley", [[0, 50], [50, 90], [100, 90], [150, 60]], "VALLEY", pattern)
    old.objects.link(valley)  # also in the excluded sub-collection: still shown (a review session: left out)
    hidden = crease("Hidden", [[0, 100], [50, 130], [100, 130], [150, 110]], "MOUNTAIN", pattern)
    disabled = crease("Disabled", [[50, 0], [60, 50], [60, 100], [50, 150]], "MOUNTAIN", pattern)
    crease("Excluded", [[100, 0], [110, 50], [110, 100], [100, 150]], "MOUNTAIN", old)
    bpy.context.view_layer.update()
    hidden.hide_set(True)
    disabled.hide_viewport = True
    bpy.context.view_layer.layer_collection.children["Pattern"].children["Old"].exclude = True
    bpy.context.view_layer.update()
    kept, notes = curves_mod.shown_crease_curves(pattern)
    assert sorted(ob.name for ob in kept) == ["Border", "Valley"]
    assert len(notes) == 1 and notes[0].startswith("3 hidden crease curve(s) of 'Pattern' left out: ")
    assert all(f"'{name}'" in notes[0] for name in ("Hidden", "Disabled", "Excluded"))
    assert bpy.ops.curved_fold.fold(collection="Pattern") == {"FINISHED"}
    faces = bpy.context.active_object.curved_fold_mesh.last_faces
    path = tmp_path / "hidden.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path), copy=True)
    for collection in (None, "Pattern"):
        pattern_read = reader.read_pattern(path, collection=collection)
        assert pipeline.fold_pattern(pattern_read).report["faces"] == faces, collection
        assert any("hidden crease curve(s)" in w for w in pattern_read.warnings), collection
    visible_only = reader.read_pattern(path, collection="Pattern")
    assert visible_only.count("M") == 0 and visible_only.count("V") > 0
    # a collection excluded from the view layer folds too (the fold, made beside its curves, is not selectable:
    # selecting it raised a traceback)
    bpy.context.view_layer.layer_collection.children["Pattern"].exclude = True
    bpy.context.view_layer.update()
    made = set(bpy.data.objects)
    assert bpy.ops.curved_fold.fold(collection="Pattern") == {"FINISHED"}
    assert any(
        getattr(ob, "curved_fold_mesh", None) and ob.curved_fold_mesh.is_fold_mesh
        for ob in set(bpy.data.objects) - made
    )
