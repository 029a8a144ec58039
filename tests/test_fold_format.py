"""FOLD reading/writing, lossless round trips, reader dispatch and atomic files."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from curved_fold.core.io.atomic import atomic_write_bytes, atomic_write_text
from curved_fold.core.io.fold import (
    fold_to_mesh,
    fold_to_pattern,
    folded_to_fold,
    parse_fold,
    read_fold,
    write_folded_fold,
    write_pattern_fold,
)
from curved_fold.core.io.reader import read_curves, read_pattern
from curved_fold.core.mesh.fold_mesh import FoldMesh
from curved_fold.core.pattern.discretize import discretize
from curved_fold.core.pattern.model import CreaseCurve, CurveSegment, PatternError

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "origami-simulator"
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

SQUARE = {
    "vertices_coords": [[0, 0], [10, 0], [10, 10], [0, 10]],
    "edges_vertices": [[0, 1], [1, 2], [2, 3], [3, 0], [0, 2]],
    "edges_assignment": ["B", "B", "B", "B", "V"],
    "edges_foldAngle": [None, None, None, None, 90],
    "faces_vertices": [[0, 1, 2], [0, 2, 3]],
}


def fold_text(**changes) -> str:
    data = json.loads(json.dumps(SQUARE))
    for k, v in changes.items():
        if v is None:
            data.pop(k, None)
        else:
            data[k] = v
    return json.dumps(data)


def assert_same_pattern(a, b) -> None:
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_array_equal(a.edges, b.edges)
    np.testing.assert_array_equal(a.assignments, b.assignments)
    np.testing.assert_array_equal(a.fold_angles, b.fold_angles)  # nan == nan for array_equal on floats
    np.testing.assert_array_equal(a.edge_polyline, b.edge_polyline)
    np.testing.assert_array_equal(a.edge_from_curve, b.edge_from_curve)
    assert a.sources == b.sources


def assert_same_mesh(a: FoldMesh, b: FoldMesh) -> None:
    for name in ("vertices", "triangles", "edges", "assignments", "fold_angles", "edge_polyline", "edge_from_curve"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    np.testing.assert_array_equal(a.triangle_face, b.triangle_face)
    assert a.sources == b.sources and a.mesh_type == b.mesh_type
    assert [f.tolist() for f in map(np.asarray, a.faces)] == [f.tolist() for f in b.faces]


# ------------------------------------------------------------------------------------------------ round trips


@pytest.mark.parametrize(
    "path",
    [FIXTURES / "wavy_pleats.svg", FIXTURES / "huffmanTower.svg", FIXTURES / "Treble_Clef.svg"]
    + [EXAMPLES / "curved_border.svg", EXAMPLES / "concentric_arcs.svg"],
    ids=lambda p: p.name,
)
def test_svg_to_fold_and_back_is_lossless(path: Path, tmp_path: Path) -> None:
    pattern = read_pattern(path)
    out = tmp_path / "p.fold"
    written = write_pattern_fold(out, pattern)
    assert written == out.resolve()
    back = read_pattern(out)
    assert_same_pattern(pattern, back)
    data = json.loads(out.read_text())
    assert data["frame_classes"] == ["creasePattern"] and data["frame_unit"] == "mm"
    assert data["file_spec"] == 1.1 and len(data["curved_fold:edge_from_curve"]) == pattern.n_edges
    # and once more through the file: byte-identical
    out2 = tmp_path / "p2.fold"
    write_pattern_fold(out2, back)
    assert out2.read_bytes() == out.read_bytes()


def test_a_pattern_with_cuts_says_fold_1_2(tmp_path: Path) -> None:
    """Cut ("C") edges came with FOLD 1.2: a pattern that has them says so (it said 1.1), with the "cuts" frame
    attribute the spec recommends."""
    border = CreaseCurve(
        [
            CurveSegment("line", np.array(p, float))
            for p in ([[0, 0], [10, 0]], [[10, 0], [10, 10]], [[10, 10], [0, 10]], [[0, 10], [0, 0]])
        ],
        "B",
        None,
        source="border",
    )
    cut = CreaseCurve([CurveSegment("line", np.array([[3.0, 5.0], [7.0, 5.0]]))], "C", None, source="slit")
    data = json.loads(write_pattern_fold(tmp_path / "c.fold", discretize([border, cut])).read_text())
    assert data["file_spec"] == 1.2 and "cuts" in data["frame_attributes"]


def square_mesh() -> FoldMesh:
    return FoldMesh(
        vertices=[[0, 0], [10, 0], [10, 10], [0, 10]],
        triangles=[[0, 1, 2], [0, 2, 3]],
        edges=[[0, 1], [1, 2], [2, 3], [0, 3], [0, 2]],
        assignments=["B", "B", "B", "B", "V"],
        fold_angles=[np.nan, np.nan, np.nan, np.nan, 90.0],
        edge_from_curve=[False] * 4 + [True],
        edge_polyline=[0, 0, 0, 0, 1],
        triangle_face=[0, 0],
        sources=["border", "crease"],
        mesh_type="ruling",
    )


def test_folded_fold_follows_the_spec_and_reads_back(tmp_path: Path) -> None:
    """Key frame = the flat crease pattern (creasePattern, 2D, numeric target angles); the folded states are
    file_frames (foldedForm, 3D, their own simulated angles); two of them make an animation."""
    mesh = square_mesh()
    f0 = np.column_stack([mesh.vertices, np.zeros(4)])
    f1 = f0.copy()
    f1[3] = [5, 5, 7.0710678]
    angles = [np.array([np.nan] * 4 + [88.5]), np.array([np.nan] * 4 + [0.0])]  # per frame: folded, flat
    out = tmp_path / "folded.fold"
    write_folded_fold(out, mesh, [f1, f0], angles, extra={"curved_fold:percent": 1.0})
    data = json.loads(out.read_text())
    assert data["frame_classes"] == ["creasePattern"] and data["frame_attributes"] == ["2D"]
    assert data["file_classes"] == ["singleModel", "animation"]
    assert data["vertices_coords"] == [[0, 0], [10, 0], [10, 10], [0, 10]]
    assert data["faces_vertices"] == [[0, 1, 2], [0, 2, 3]]
    assert data["edges_foldAngle"] == [0, 0, 0, 0, 90.0]  # numbers everywhere, 0 for the border
    frames = data["file_frames"]
    assert [f["frame_classes"] for f in frames] == [["foldedForm"], ["foldedForm"]]
    assert frames[0]["vertices_coords"][3] == [5, 5, 7.0710678] and frames[0]["edges_foldAngle"] == [0] * 4 + [88.5]
    assert frames[0]["frame_parent"] == 0 and frames[0]["frame_inherit"] is True
    assert data["curved_fold:percent"] == 1.0
    doc = read_fold(out)
    assert len(doc.frames) == 2
    np.testing.assert_array_equal(doc.frames[0], f1)
    np.testing.assert_array_equal(doc.frames[1], f0)
    np.testing.assert_array_equal(doc.vertices, mesh.vertices)
    np.testing.assert_array_equal(doc.frame_fold_angles[0], [0] * 4 + [88.5])
    pattern = fold_to_pattern(doc)
    assert pattern.count("V") == 1 and pattern.sources == ["border", "crease"]
    assert pattern.edge_from_curve.tolist() == [False] * 4 + [True]
    assert np.isnan(pattern.fold_angles[:4]).all()  # the border's 0 is "no angle" again
    back = fold_to_mesh(doc)
    assert_same_mesh(mesh, back)
    single = json.loads(json.dumps(folded_to_fold(mesh, [f1])))
    assert single["file_classes"] == ["singleModel"] and len(single["file_frames"]) == 1


def test_folded_fold_writes_a_crease_driven_past_flat_as_folded_flat(tmp_path: Path) -> None:
    """The solver's angles are unwrapped (Carved_Cylinder at 100 % has a valley at 192°: no contact, the layers pass
    through). The spec's range is [−180°, 180°] with the assignment's sign, and our reader refuses anything else:
    the frame says 180° (folded flat) and the file reads back."""
    mesh = square_mesh()
    f0 = np.column_stack([mesh.vertices, np.zeros(4)])
    out = tmp_path / "past_flat.fold"
    write_folded_fold(out, mesh, [f0, f0], [np.array([np.nan] * 4 + [192.1]), np.array([np.nan] * 4 + [-200.0])])
    frames = json.loads(out.read_text())["file_frames"]
    assert frames[0]["edges_foldAngle"][4] == 180.0 and frames[1]["edges_foldAngle"][4] == -180.0
    doc = read_fold(out)
    np.testing.assert_array_equal(doc.frame_fold_angles[0], [0] * 4 + [180.0])


def test_folded_fold_in_cm_and_shape_errors(tmp_path: Path) -> None:
    mesh = square_mesh()
    f0 = np.column_stack([mesh.vertices, np.ones(4)])
    write_folded_fold(tmp_path / "cm.fold", mesh, [f0], unit="cm")
    data = json.loads((tmp_path / "cm.fold").read_text())
    assert data["file_frames"][0]["vertices_coords"][1] == [1.0, 0.0, 0.1] and data["frame_unit"] == "cm"
    assert data["vertices_coords"][1] == [1.0, 0.0]
    doc = read_fold(tmp_path / "cm.fold")  # read back in mm
    np.testing.assert_allclose(doc.frames[0], f0)
    np.testing.assert_allclose(doc.vertices, mesh.vertices)
    with pytest.raises(PatternError, match=r"frame 0 has shape \(3, 3\), expected \(4, 3\)"):
        write_folded_fold(tmp_path / "x.fold", mesh, [f0[:3]])
    with pytest.raises(PatternError, match="fold angles of frame 0 have 2 entries, mesh has 5 edges"):
        write_folded_fold(tmp_path / "x.fold", mesh, [f0], [np.zeros(2)])
    with pytest.raises(PatternError, match="no frame"):
        write_folded_fold(tmp_path / "x.fold", mesh, [])
    assert not (tmp_path / "x.fold").exists()


def test_legacy_folded_file_with_flat_coords_still_reads() -> None:
    """Files written before the key frame became the crease pattern: folded key frame + curved_fold:flat_coords."""
    legacy = fold_text(
        vertices_coords=[[0, 0, 0], [10, 0, 0], [10, 10, 0], [5, 5, 7]],
        **{"curved_fold:flat_coords": SQUARE["vertices_coords"], "curved_fold:edge_polyline": [0, 0, 0, 0, -1]},
    )
    doc = parse_fold(legacy, "old.fold")
    assert len(doc.frames) == 1 and doc.frames[0][3, 2] == 7
    p = fold_to_pattern(doc)  # the -1 (triangulation diagonal) is dropped, not "out of range"
    assert p.n_edges == 4 and p.count("B") == 4


# ------------------------------------------------------------------------------------------------ reading


def test_plain_fold_reading_defaults() -> None:
    doc = parse_fold(fold_text(edges_assignment=["b", "b", "b", "b", "m"], edges_foldAngle=None), "s.fold")
    p = fold_to_pattern(doc)
    assert p.assignments.tolist() == ["B", "B", "B", "B", "M"]
    assert np.isnan(p.fold_angles).all()  # no angles given: the fold --angle option fills them
    assert p.sources[4] == "s.fold edge 4" and p.edge_polyline.tolist() == [0, 1, 2, 3, 4]
    assert doc.faces == [[0, 1, 2], [0, 2, 3]]


def test_v10_spelling_3d_flat_and_units() -> None:
    text = fold_text(
        edges_foldAngle=None,
        edges_foldAngles=[None, None, None, None, 45],
        vertices_coords=[[0, 0, 0], [1, 0, 0], [1, 1, 1e-15], [0, 1, 0]],
        frame_unit="cm",
    )
    doc = parse_fold(text, "v1.fold")
    p = fold_to_pattern(doc)
    assert p.fold_angles[4] == 45
    np.testing.assert_allclose(p.vertices, [[0, 0], [10, 0], [10, 10], [0, 10]])
    assert doc.frames == []


def test_a_fold_angle_of_the_other_sign_than_its_assignment_folds_as_assigned() -> None:
    """A valley at −180° was folded as a mountain without a word (a CLI review session): the assignment, which the
    drawing shows and an SVG's colour gives, sets the sign, and a warning names the edge."""
    doc = parse_fold(fold_text(edges_foldAngle=[None, None, None, None, -180]), "sign.fold")
    assert fold_to_pattern(doc).fold_angles[4] == 180
    assert any(
        w.startswith("sign.fold: edges_foldAngle[4] = -180 on a valley (edges_assignment V): FOLD folds valleys")
        for w in doc.warnings
    ), doc.warnings
    doc = parse_fold(fold_text(edges_foldAngle=[None, None, None, None, 90]), "ok.fold")
    assert fold_to_pattern(doc).fold_angles[4] == 90 and not any("FOLD folds" in w for w in doc.warnings)


def test_folded_3d_file_without_flat_coordinates() -> None:
    doc = parse_fold(fold_text(vertices_coords=[[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 5]]), "f.fold")
    assert len(doc.frames) == 1 and doc.vertices is None
    with pytest.raises(PatternError, match="f.fold: a folded \\(3D\\) FOLD file without a flat crease pattern"):
        fold_to_pattern(doc)


def test_file_frames_inherit_from_parent() -> None:
    frames = [
        {"frame_inherit": True, "frame_parent": 0, "vertices_coords": [[0, 0, 1], [10, 0, 0], [10, 10, 0], [0, 10, 0]]},
        {"frame_inherit": True, "frame_parent": 1},
    ]
    doc = parse_fold(fold_text(file_frames=frames), "fr.fold")
    assert len(doc.frames) == 2
    np.testing.assert_array_equal(doc.frames[0], doc.frames[1])
    assert doc.frames[1][0, 2] == 1


@pytest.mark.parametrize(
    "changes,message",
    [
        ({"vertices_coords": None}, "missing required array vertices_coords"),
        ({"edges_assignment": None}, "missing required array edges_assignment"),
        ({"edges_assignment": ["B"] * 4}, "edges_assignment has 4 entries but edges_vertices has 5"),
        ({"edges_foldAngle": [0] * 6}, "edges_foldAngle has 6 entries but edges_vertices has 5"),
        ({"edges_vertices": [[0, 1], [1, 7]]}, r"edges_vertices\[1\] = \[1, 7\]: index 7 out of range \(4 vertices\)"),
        ({"edges_vertices": [[0, 1], [1]]}, r"edges_vertices\[1\] = \[1\]: expected 2 vertex indices"),
        ({"edges_assignment": ["B", "B", "X", "B", "V"]}, r"edges_assignment\[2\] = 'X' is not one of"),
        ({"faces_vertices": [[0, 1, 9]]}, r"faces_vertices\[0\] = \[0, 1, 9\]: index 9 out of range"),
        ({"faces_vertices": [[0, 1, 2], []]}, r"faces_vertices\[1\] = \[\]: a face needs at least 3 vertices"),
        ({"faces_vertices": [[0, 1]]}, r"faces_vertices\[0\] = \[0, 1\]: a face needs at least 3 vertices"),
        ({"vertices_coords": [[0, 0], [1, 0], [1, "a"], [0, 1]]}, r"vertices_coords\[2\] = \[1, 'a'\]"),
        ({"vertices_coords": [[0, 0], [1, 0], [1], [0, 1]]}, r"vertices_coords\[2\] = \[1\]"),
        ({"edges_foldAngle": [0, 0, 0, 0, "x"]}, r"edges_foldAngle\[4\] = 'x' is not a finite number"),
        ({"file_frames": [{"vertices_coords": [[0, 0]]}]}, r"file_frames\[0\]\.vertices_coords has 1 entries"),
    ],
)
def test_fold_errors_name_the_array_and_index(changes: dict, message: str) -> None:
    with pytest.raises(PatternError, match=message) as exc:
        parse_fold(fold_text(**changes), "bad.fold")
    assert str(exc.value).startswith("bad.fold: ")


def test_non_finite_and_malformed_json() -> None:
    text = fold_text().replace("[10, 10]", "[NaN, 10]")
    with pytest.raises(PatternError, match=r"vertices_coords\[2\] = \[nan, 10\] has a non-finite coordinate"):
        parse_fold(text, "n.fold")
    with pytest.raises(PatternError, match=r"m.fold: malformed JSON at line 3, column 1"):
        parse_fold('{"vertices_coords": [\n[0, 0],\n}', "m.fold")
    with pytest.raises(PatternError, match="must be a JSON object"):
        parse_fold("[1, 2]", "a.fold")


# ------------------------------------------------------------------------------------------------ reader, files


def test_reader_dispatch_and_errors(tmp_path: Path) -> None:
    (tmp_path / "x.dxf").write_text("0")
    with pytest.raises(PatternError, match=r"x.dxf: unknown file type '.dxf'; expected one of .svg, .fold, .blend"):
        read_pattern(tmp_path / "x.dxf")
    with pytest.raises(PatternError, match="no such file"):
        read_pattern(tmp_path / "missing.svg")
    fold = tmp_path / "s.fold"
    fold.write_text(fold_text())
    assert read_pattern(fold).count("V") == 1
    fold_curves, _ = read_curves(fold)  # FOLD segments come back as straight polylines, one per chain
    pat = read_pattern(fold)
    assert all(seg.kind == "line" for c in fold_curves for seg in c.segments)
    for a in set(pat.assignments.tolist()):
        assert sum(len(c.segments) for c in fold_curves if c.assignment == a) == pat.count(a)
    curves, warnings = read_curves(EXAMPLES / "single_curve.svg")
    assert len(curves) == 2 and warnings == []
    p = read_pattern(EXAMPLES / "single_curve.svg", interval=3.0, tolerance=0.01)
    q = read_pattern(EXAMPLES / "single_curve.svg")
    assert p.count("V") > q.count("V")


def test_reader_passes_svg_warnings_on(tmp_path: Path) -> None:
    f = tmp_path / "w.svg"
    f.write_text(
        '<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10" width="10mm" height="10mm">'
        '<line stroke="red" x1="0" y1="0" x2="10" y2="10"/><line stroke="#abc" x2="3"/></svg>'
    )
    p = read_pattern(f)
    assert p.warnings and "unknown stroke colours" in p.warnings[0] and "#abc" in p.warnings[0]


def test_atomic_writes_replace_whole_files_and_leave_nothing_on_failure(tmp_path: Path) -> None:
    target = tmp_path / "a.txt"
    atomic_write_text(target, "first")
    atomic_write_bytes(target, b"second")
    assert target.read_bytes() == b"second"
    assert sorted(os.listdir(tmp_path)) == ["a.txt"]
    with pytest.raises(OSError):
        atomic_write_text(tmp_path / "missing" / "b.txt", "x")
    with pytest.raises(TypeError):
        atomic_write_bytes(target, "not bytes")  # type: ignore[arg-type]
    assert target.read_bytes() == b"second" and sorted(os.listdir(tmp_path)) == ["a.txt"]


def test_atomic_writes_get_ordinary_file_modes(tmp_path: Path) -> None:
    """A new file gets 0o666 less the umask (not a temporary file's private 0o600); an existing file keeps its mode."""
    import os
    import stat

    from curved_fold.core.io.atomic import atomic_write_text

    old = os.umask(0o022)
    try:
        new = atomic_write_text(tmp_path / "new.fold", "{}")
        assert stat.S_IMODE(new.stat().st_mode) == 0o644
        kept = tmp_path / "kept.fold"
        kept.write_text("x")
        kept.chmod(0o640)
        atomic_write_text(kept, "{}")
        assert stat.S_IMODE(kept.stat().st_mode) == 0o640
    finally:
        os.umask(old)


@pytest.mark.parametrize(
    ("unit", "size", "said"),
    [
        (None, 1.0, "no frame_unit (unitless coordinates, read as millimetres): the sheet is 1 mm across"),
        ("unit", 1.0, 'frame_unit "unit" (unitless coordinates, read as millimetres): the sheet is 1 mm across'),
        (None, 400.0, None),  # ORIPA's 400-unit square: a sheet of a real size
        ("mm", 1.0, None),  # a millimetre sheet, said so
    ],
)
def test_a_unitless_unit_square_is_said_to_be_read_as_millimetres(unit, size, said) -> None:
    """Rabbit Ear and the FOLD spec's examples draw a unit square without a unit: read as millimetres it folded
    silently into a 1 mm model (a designer session's 0.7 mm STL, fifteenth pass). A unitless sheet under 10 mm is
    now said to be one; a unitless sheet of a real size, or a unit given, is read as before."""
    doc = {
        "vertices_coords": [[0, 0], [size, 0], [size, size], [0, size]],
        "edges_vertices": [[0, 1], [1, 2], [2, 3], [3, 0], [0, 2]],
        "edges_assignment": ["B", "B", "B", "B", "V"],
        "edges_foldAngle": [0, 0, 0, 0, 90],
    }
    if unit is not None:
        doc["frame_unit"] = unit
    warnings = [w for w in parse_fold(json.dumps(doc), "sq.fold").warnings if "unitless" in w]
    assert warnings == (
        []
        if said is None
        else [f"sq.fold: {said}; scale the file for a real size (the folded shape is the same at any size)"]
    )
