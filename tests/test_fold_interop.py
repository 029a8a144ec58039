"""FOLD files from and for other tools: our folded files read back, Origami Simulator's files, FOLD 1.2 ``J`` edges,
coincident vertices (the FOLD library's own ``diagonal-folded.fold``) refused with exit 2 before triangulation."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from curved_fold.core.io.fold import (
    flat_plane,
    fold_to_mesh,
    fold_to_pattern,
    parse_fold,
    pattern_for_folding,
    read_fold,
    write_folded_fold,
)
from curved_fold.core.io.reader import read_pattern
from curved_fold.core.pattern.model import PatternError
from curved_fold.core.pipeline import fold_pattern

FIXTURES = Path(__file__).resolve().parent / "fixtures"
OS = FIXTURES / "origami-simulator"
REPO = Path(__file__).resolve().parents[1]

SLIT_SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="60mm" viewBox="0 0 100 60">
<polygon stroke="#000000" fill="none" points="0,0 100,0 100,60 0,60"/>
<line stroke="#00ff00" x1="30" y1="30" x2="70" y2="30"/>
<line stroke="#0000ff" opacity="0.5" x1="50" y1="0" x2="50" y2="20"/>
<line stroke="#ff0000" opacity="0.5" x1="50" y1="40" x2="50" y2="60"/>
</svg>
"""


def _same_mesh(a, b) -> None:
    for name in ("vertices", "triangles", "edges", "assignments", "fold_angles", "edge_polyline", "edge_from_curve"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    np.testing.assert_array_equal(a.triangle_face, b.triangle_face)
    assert a.sources == b.sources and a.mesh_type == b.mesh_type


@pytest.mark.parametrize("svg", ["wavy_pleats.svg", "slit"])
def test_our_folded_file_reads_back_to_the_same_mesh_and_pattern(svg: str, tmp_path: Path) -> None:
    if svg == "slit":
        (tmp_path / "slit.svg").write_text(SLIT_SVG)
        path = tmp_path / "slit.svg"
    else:
        path = OS / svg
    pattern = read_pattern(path)
    run = fold_pattern(pattern)
    out = tmp_path / "folded.fold"
    half = 0.5 * (run.mesh.vertices_3d + run.result.positions)
    write_folded_fold(out, run.mesh, [half, run.result.positions], [run.result.fold_angles] * 2)
    doc = read_fold(out)
    # every frame back, in order
    assert len(doc.frames) == 2
    np.testing.assert_allclose(doc.frames[1], run.result.positions, rtol=0, atol=1e-12)
    np.testing.assert_allclose(doc.frames[0], half, rtol=0, atol=1e-12)
    _same_mesh(run.mesh, fold_to_mesh(doc))
    # the crease pattern comes back (diagonals dropped, slits merged back into cuts) and folds to the same mesh
    again = fold_to_pattern(doc)
    assert again.n_edges == pattern.n_edges and again.n_vertices == pattern.n_vertices
    for a in "BMVCFU":
        assert again.count(a) == pattern.count(a), a
    rerun = fold_pattern(again)
    assert rerun.mesh.n_faces == run.mesh.n_faces and len(rerun.mesh.edges) == len(run.mesh.edges)
    np.testing.assert_allclose(np.sort(rerun.mesh.vertices, axis=0), np.sort(run.mesh.vertices, axis=0))


def _origami_simulator_fold(pattern, plane: str) -> dict:
    """A crease pattern as Origami Simulator's saveFOLD writes it (reference §5.7): 3D, the sheet at y = 0 with the
    SVG's (x, y_down) as (x, 0, y), ``foldedForm``, unit ``"unit"``, cuts written as borders, target angles."""
    x, y_up = pattern.vertices[:, 0], pattern.vertices[:, 1]
    if plane == "y":
        coords = np.column_stack([x, np.zeros_like(x), -y_up])
    elif plane == "x":
        coords = np.column_stack([np.full_like(x, 3.0), x, y_up])
    else:
        coords = np.column_stack([x, y_up, np.full_like(x, -2.0)])
    return {
        "file_spec": 1.1,
        "file_creator": "Origami Simulator: http://git.amandaghassaei.com/OrigamiSimulator/",
        "file_classes": ["singleModel"],
        "frame_classes": ["foldedForm"],
        "frame_attributes": ["3D"],
        "frame_unit": "unit",
        "vertices_coords": coords.tolist(),
        "edges_vertices": pattern.edges.tolist(),
        "edges_assignment": np.where(pattern.assignments == "C", "B", pattern.assignments).tolist(),
        "edges_foldAngle": np.nan_to_num(pattern.fold_angles).tolist(),
    }


@pytest.mark.parametrize("plane", ["y", "x", "z"])
def test_origami_simulator_flat_3d_files_read_as_the_pattern_and_fold(plane: str) -> None:
    pattern = read_pattern(OS / "curvedPleatSimple.svg")
    doc = parse_fold(json.dumps(_origami_simulator_fold(pattern, plane)), "os.fold")
    assert doc.frames == []  # flat, whatever its class says
    back = fold_to_pattern(doc)
    np.testing.assert_allclose(back.vertices, pattern.vertices, atol=1e-12)  # same orientation: M/V keep their sense
    np.testing.assert_array_equal(back.assignments, pattern.assignments)
    ours, theirs = fold_pattern(pattern), fold_pattern(back)
    assert theirs.result.converged and theirs.mesh.n_faces == ours.mesh.n_faces
    np.testing.assert_allclose(theirs.result.positions, ours.result.positions, atol=1e-6 * pattern.size)


def test_flat_plane_detection() -> None:
    folded = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.3]])
    assert flat_plane(folded) is None
    np.testing.assert_array_equal(flat_plane(np.array([[1, 0, 2], [3, 0, 4], [5, 0, 1]])), [[1, -2], [3, -4], [5, -1]])


def test_join_edges_are_dropped_and_their_faces_merge() -> None:
    data = {
        "file_spec": 1.2,
        "frame_attributes": ["2D", "joins"],
        "vertices_coords": [[0, 0], [10, 0], [10, 10], [0, 10], [5, 0], [5, 10], [20, 20]],
        "edges_vertices": [[0, 4], [4, 1], [1, 2], [2, 5], [5, 3], [3, 0], [4, 5], [0, 2], [2, 6]],
        "edges_assignment": ["B", "B", "B", "B", "B", "B", "V", "J", "J"],
        "edges_foldAngle": [0, 0, 0, 0, 0, 0, 90, 0, 0],
    }
    p = fold_to_pattern(parse_fold(json.dumps(data), "j.fold"))
    assert p.n_edges == 7 and "J" not in p.assignments.tolist()
    assert p.n_vertices == 6  # vertex 6 was only on a join edge
    assert p.fold_angles[6] == 90 and np.isnan(p.fold_angles[:6]).all()
    run = fold_pattern(p)
    assert run.result.converged and 85 < run.result.fold_angles[np.flatnonzero(run.mesh.assignments == "V")[0]] < 95
    bad = dict(data, edges_assignment=["B"] * 6 + ["V", "X", "J"])
    with pytest.raises(PatternError, match=r"edges_assignment\[7\] = 'X' is not one of B, M, V, F, U, C, J"):
        parse_fold(json.dumps(bad), "j.fold")


def test_coincident_vertices_are_merged_or_refused_before_triangulation() -> None:
    data = {
        "vertices_coords": [[0, 0], [10, 0], [10, 10], [0, 10], [10, 0]],
        "edges_vertices": [[0, 1], [1, 2], [2, 3], [3, 0], [0, 2], [4, 3]],
        "edges_assignment": ["B", "B", "B", "B", "V", "M"],
    }
    p = fold_to_pattern(parse_fold(json.dumps(data), "c.fold"))  # a vertex drawn twice: merged
    assert p.n_vertices == 4 and p.edges[5].tolist() == [1, 3]
    data["edges_vertices"][5] = [4, 2]  # now a crease lies on the border: refused with both vertices named
    with pytest.raises(PatternError, match=r"c.fold: vertices 1 and 4 coincide at \(10, 0\); edge 5 \(M\) then lies"):
        fold_to_pattern(parse_fold(json.dumps(data), "c.fold"))


def test_a_vertex_written_twice_merges_in_the_reader_and_the_triangulation_still_refuses_it_raw() -> None:
    """A FOLD file's duplicate vertex is merged by the reader (so it folds); a pattern handed over with the duplicate
    still gets the triangulation's own one-line refusal (moved here from test_robust_inputs)."""
    from curved_fold.core.pattern.model import CreasePattern

    data = {
        "vertices_coords": [[0, 0], [1, 0], [1, 1], [0, 1], [1, 1]],
        "edges_vertices": [[0, 1], [1, 2], [4, 3], [3, 0], [0, 2]],
        "edges_assignment": ["B", "B", "B", "B", "V"],
    }
    p = fold_to_pattern(parse_fold(json.dumps(data), "sq.fold"))
    assert p.n_vertices == 4 and p.edges[2].tolist() == [2, 3]
    assert fold_pattern(p, angle=90).result.converged
    raw = CreasePattern(
        vertices=data["vertices_coords"],
        edges=data["edges_vertices"],
        assignments=data["edges_assignment"],
        fold_angles=[np.nan] * 4 + [90.0],
        edge_polyline=range(5),
        edge_from_curve=[False] * 5,
    )
    with pytest.raises(PatternError, match=r"triangulation: pattern vertex 4 at \[1\.0, 1\.0\] mm is not in the"):
        fold_pattern(raw, angle=90)


@pytest.mark.parametrize("mesh", ["ruling", "cdt", "earcut"])
def test_fold_library_flat_folded_example_exits_2_with_one_line(mesh: str, tmp_path: Path) -> None:
    """The FOLD library's ``diagonal-folded.fold`` (a flat-folded state: vertices coincide) once crashed the process
    inside the triangulation (exit 139); now the reader refuses it with one line and exit code 2."""
    proc = subprocess.run(
        [sys.executable, "-m", "curved_fold", "fold", str(FIXTURES / "fold" / "diagonal-folded.fold")]
        + ["--out", str(tmp_path / "o.fold"), "--mesh", mesh],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=REPO,
    )
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "vertices 0 and 2 coincide" in lines[0] and "Traceback" not in proc.stderr
    assert not (tmp_path / "o.fold").exists()


def test_fold_library_crease_pattern_example_folds(tmp_path: Path) -> None:
    doc = read_fold(FIXTURES / "fold" / "diagonal-cp.fold")
    run = fold_pattern(fold_to_pattern(doc), percent=0.5)
    assert run.result.converged and run.mesh.n_faces == 2


def test_another_tools_dense_polylines_are_thinned_as_a_drawings(tmp_path: Path) -> None:
    """A FOLD file from another tool stores each curve as its own polyline: three sine creases of 200 points each
    on a 150 × 100 mm sheet (a designer session's CAD-style file, fifteenth pass). Kept point for point, the
    triangulation fanned 20 mm triangles onto their 0.5 mm pieces: 1,264 faces, 495 corners under 1°. Thinned as
    the same polylines drawn in an SVG are, it meshes as that drawing does; the file's edges still name the
    creases (a curve's, as one stroke)."""
    from curved_fold.core.mesh.build import build_mesh
    from curved_fold.core.mesh.fold_mesh import corner_angles

    s = np.linspace(0.0, 1.0, 200)
    coords = [[0.0, 0.0], [150.0, 0.0], [150.0, 100.0], [0.0, 100.0]]
    edges = [[0, 1], [1, 2], [2, 3], [3, 0]]
    assign, angles = ["B"] * 4, [0.0] * 4
    polylines = []
    for k, x0 in enumerate((40.0, 75.0, 110.0)):
        pts = [[x0 + 8.0 * np.sin(2 * np.pi * t), 100.0 * t] for t in s]
        pts[0][1], pts[-1][1] = 0.0, 100.0
        polylines.append(pts)
        first = len(coords)
        coords += pts
        edges += [[first + i, first + i + 1] for i in range(len(pts) - 1)]
        assign += ["M" if k % 2 else "V"] * (len(pts) - 1)
        angles += [-90.0 if k % 2 else 90.0] * (len(pts) - 1)
    # the border through the creases' ends: split the bottom and top edges there (a planar graph, as FOLD wants)
    bottom = [0, *(4 + 200 * k for k in range(3)), 1]
    top = [2, *(4 + 200 * k + 199 for k in range(2, -1, -1)), 3]
    edges[:4] = [[bottom[i], bottom[i + 1]] for i in range(4)] + [[1, 2]] + [[3, 0]]
    edges += [[top[i], top[i + 1]] for i in range(4)]
    assign = ["B"] * 6 + assign[4:] + ["B"] * 4
    angles = [0.0] * 6 + angles[4:] + [0.0] * 4
    doc = {"file_spec": 1.1, "frame_unit": "mm", "vertices_coords": coords, "edges_vertices": edges}
    doc |= {"edges_assignment": assign, "edges_foldAngle": angles}
    path = tmp_path / "cad.fold"
    path.write_text(json.dumps(doc))
    svg = tmp_path / "cad.svg"
    lines = "".join(
        f'<polyline points="{" ".join(f"{float(x)!r},{-float(y)!r}" for x, y in pts)}" fill="none" '
        f'stroke="{"#ff0000" if k % 2 else "#0000ff"}" opacity="0.5"/>'
        for k, pts in enumerate(polylines)
    )
    svg.write_text(
        '<svg xmlns="http://www.w3.org/2000/svg" width="150mm" height="100mm" viewBox="0 -100 150 100">'
        '<rect x="0" y="-100" width="150" height="100" fill="none" stroke="#000000"/>' + lines + "</svg>"
    )
    fold, drawn = build_mesh(read_pattern(path)), build_mesh(read_pattern(svg))
    assert corner_angles(fold.vertices, fold.triangles).min() > 1.0
    assert fold.n_faces == drawn.n_faces < 300
    creases = read_pattern(path)
    named = {creases.sources[k] for k in creases.edge_polyline[creases.assignments == "M"]}
    assert named and all(name.startswith("cad.fold edges ") for name in named)  # one stroke per curve


def _dense_fold(tmp_path: Path, name: str, extra: list[tuple[list[list[float]], str]], size: float = 100.0) -> Path:
    """A ``size`` mm FOLD sheet (border as four edges) with the closed or open polylines ``extra`` ((points,
    role))."""
    coords = [[0.0, 0.0], [size, 0.0], [size, size], [0.0, size]]
    edges, assign, angles = [[0, 1], [1, 2], [2, 3], [3, 0]], ["B"] * 4, [0.0] * 4
    for pts, role in extra:
        closed = pts[0] == pts[-1]
        first = len(coords)
        coords += pts[:-1] if closed else pts
        n = len(pts) - 1
        edges += [[first + i, first + (i + 1) % n if closed else first + i + 1] for i in range(n)]
        assign += [role] * n
        angles += [0.0 if role == "C" else 90.0] * n
    path = tmp_path / name
    doc = {"file_spec": 1.1, "frame_unit": "mm", "vertices_coords": coords, "edges_vertices": edges}
    path.write_text(json.dumps(doc | {"edges_assignment": assign, "edges_foldAngle": angles}))
    return path


def test_another_tools_narrow_closed_loop_is_not_thinned_onto_itself(tmp_path: Path) -> None:
    """A 6 × 0.1 mm slot drawn as a closed 120-point cut (a review session's laser-cut outline): thinned from its one
    stop, its two long sides became chords between the same two vertices, and the fold stopped with "pattern edges
    4 and 5 join the same two vertices". A loop keeps three vertices at least, and a chord keeps clear of the rest
    of its own chain (the slot's far side)."""
    t = np.linspace(0.0, 2.0 * np.pi, 121)
    slot = [[75.0 + 3.0 * np.cos(a), 75.0 + 0.05 * np.sin(a)] for a in t[:-1]]
    path = _dense_fold(tmp_path, "slot.fold", [(slot + [slot[0]], "C")], size=150.0)
    report = fold_pattern(read_pattern(path)).report
    assert report["converged"]


def test_another_tools_file_is_thinned_at_the_interval_asked(tmp_path: Path) -> None:
    """``--interval`` and ``--tolerance`` apply to another tool's FOLD file, as to a drawing: its dense polylines
    are thinned at them (they were ignored, and the file thinned at the automatic interval; a review session), the
    interval is the one its creases are split at beside needles, and a bad value is refused in one line."""
    s = np.linspace(0.0, 1.0, 201)
    sine = [[50.0 + 10.0 * np.sin(2 * np.pi * u), 100.0 * u] for u in s]
    path = _dense_fold(tmp_path, "dense.fold", [(sine, "V")])
    auto, fine = read_pattern(path), read_pattern(path, interval=3.0, tolerance=0.02)
    assert math.isnan(auto.interval) and fine.interval == 3.0
    creases = [int(np.count_nonzero(p.assignments == "V")) for p in (auto, fine)]
    assert creases[0] < creases[1] < 200
    with pytest.raises(PatternError, match="interval must be a positive number of mm, got -1.0"):
        read_pattern(path, interval=-1.0)


def test_another_tools_crossing_edges_are_split_as_a_drawings(tmp_path: Path) -> None:
    """A hand-made FOLD file draws a valley across a 100 mm sheet and a cut across the valley as single edges that
    cross away from a vertex (a designer session's kirigami file). It was refused ("pattern edges 6 and 7 cross or
    touch near (50, 50) mm"), while its SVG twin folds: the drawing's planar clean-up splits crossings. Now the file
    is split there too, with a warning naming the two file edges, and folds as the file with the crossing split by
    hand does."""
    coords = [[0.0, 0.0], [100.0, 0.0], [100.0, 50.0], [100.0, 100.0], [0.0, 100.0], [0.0, 50.0]]
    coords += [[50.0, 25.0], [50.0, 75.0]]
    border = [[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [5, 0]]
    crossing = {"edges_vertices": border + [[5, 2], [6, 7]], "edges_assignment": ["B"] * 6 + ["V", "C"]}
    crossing["edges_foldAngle"] = [0.0] * 6 + [90.0, 0.0]
    split = {"edges_vertices": border + [[5, 8], [8, 2], [6, 8], [8, 7]], "edges_assignment": ["B"] * 6 + list("VVCC")}
    split["edges_foldAngle"] = [0.0] * 6 + [90.0, 90.0, 0.0, 0.0]
    runs = []
    for name, doc, extra in (("cross.fold", crossing, []), ("split.fold", split, [[50.0, 50.0]])):
        path = tmp_path / name
        path.write_text(json.dumps({"file_spec": 1.1, "frame_unit": "mm", "vertices_coords": coords + extra} | doc))
        runs.append(fold_pattern(read_pattern(path), percent=1.0))
    crossed, by_hand = runs
    assert crossed.result.converged and by_hand.result.converged
    assert crossed.mesh.n_faces == by_hand.mesh.n_faces
    assert crossed.result.energy == pytest.approx(by_hand.result.energy, rel=1e-9)
    # a T: the warning names the edge touched and the one whose end touches it, where (it named the two
    # lowest-numbered edges split anywhere: two border edges that do not touch, a review session)
    t_doc = {"edges_vertices": border + [[5, 2], [6, 8]], "edges_assignment": ["B"] * 6 + ["V", "C"]}
    t_doc["edges_foldAngle"] = [0.0] * 6 + [90.0, 0.0]
    t_path = tmp_path / "t.fold"
    t_path.write_text(
        json.dumps({"file_spec": 1.1, "frame_unit": "mm", "vertices_coords": coords + [[50.0, 50.0]]} | t_doc)
    )
    t_said = [w for w in read_pattern(t_path).warnings if "cross or touch" in w]
    assert t_said and "first t.fold edge 6 and t.fold edge 7, near (50, 50) mm" in t_said[0]
    said = [w for w in crossed.report["warnings"] if "cross or touch" in w]
    assert said == [
        "2 edge(s) cross or touch other edges away from a vertex (first cross.fold edge 6 and cross.fold edge 7, "
        "near (50, 50) mm): split there, as a drawing's crossings are"
    ]


def test_another_tools_long_border_edges_are_split_as_a_drawings(tmp_path: Path) -> None:
    """A FOLD file from another tool draws a 120 × 40 mm sheet with border edges of 30–40 mm between the ends of
    three sine-shaped creases in 0.7 mm pieces. Read for folding (``read_pattern``, the Blender import alike), its
    straight border is split into pieces no longer than the drawing's interval, as an SVG's is (paper §3.1), edge
    k's first piece still edge k: without border vertices to attach rulings to, the triangulation fanned slivers
    into the corners (smallest corner 0.06° on a helper's sine strip, mean fold-angle error 14.9° instead of 2.2°).
    Our own pattern files keep the pieces they were written with."""
    from curved_fold.core.pattern.discretize import default_parameters

    t = np.linspace(0.0, 1.0, 13)  # 3.3 mm pieces: sampled as the paper samples, not thinned
    xs = (30.0, 60.0, 90.0)
    # the outline through the creases' ends, as a planar graph: bottom 0-1-2-3-4, top 5-6-7-8-9 (right to left)
    coords = [[x, 0.0] for x in (0.0, *xs, 120.0)] + [[x, 40.0] for x in (120.0, *xs[::-1], 0.0)]
    edges = [[i, i + 1] for i in range(4)] + [[4, 5]] + [[i, i + 1] for i in range(5, 9)] + [[9, 0]]
    assign, angles = ["B"] * 10, [0.0] * 10
    for k, x0 in enumerate(xs):
        inner = len(coords)
        coords += [[x0 + 4.0 * np.sin(2 * np.pi * s), 40.0 * s] for s in t[1:-1]]
        chain = [1 + k, *range(inner, inner + len(t) - 2), 8 - k]
        edges += [[chain[i], chain[i + 1]] for i in range(len(chain) - 1)]
        assign += ["V" if k % 2 else "M"] * (len(chain) - 1)
        angles += [90.0 if k % 2 else -90.0] * (len(chain) - 1)
    data = {
        "file_spec": 1.1,
        "vertices_coords": coords,
        "edges_vertices": edges,
        "edges_assignment": assign,
        "edges_foldAngle": angles,
    }
    path = tmp_path / "strip.fold"
    path.write_text(json.dumps(data))
    raw = fold_to_pattern(read_fold(path))
    pattern = read_pattern(path)
    interval = default_parameters(120.0)[0]
    border = pattern.assignments == "B"
    a, b = pattern.vertices[pattern.edges[border, 0]], pattern.vertices[pattern.edges[border, 1]]
    assert np.hypot(*(b - a).T).max() <= interval + 1e-9 and border.sum() > 10
    m = len(raw.edges)  # edge k's first piece is still edge k; the creases are as in the file
    assert pattern.assignments[:m].tolist() == raw.assignments.tolist() == assign
    np.testing.assert_array_equal(pattern.edges[:m, 0], raw.edges[:, 0])
    crease = raw.assignments != "B"
    np.testing.assert_array_equal(pattern.edges[:m][crease], raw.edges[crease])
    split, whole = fold_pattern(pattern).report, fold_pattern(raw).report
    # here: mean fold-angle error 16° against 34°, strain at most 1.3 % against 1.6 %
    assert split["converged"] and split["fold_angle_error_mean_deg"] < 0.5 * whole["fold_angle_error_mean_deg"]
    assert split["strain_max_pct"] < whole["strain_max_pct"]


def test_an_exports_sliver_triangulation_is_left_out_and_the_sheet_meshed_along_its_rulings() -> None:
    """Origami Simulator saves its triangulation of the faces as facet (F) edges; between long curved polylines
    its earcut triangles have corners far under 1°. ``tests/data/os_export_sliver_facets.fold`` is a helper
    session's imitation of such an export (sine pleats, coordinates (x, 0, y) as its saveFOLD writes them): folded
    on those facets it did not converge (500 iterations, residual 1.5e4, "does not fold as assigned"). When the
    faces are all triangles (or, without faces, the triangles the edges close) and one with such a corner lies
    beside a facet, the facets are left out (a warning says so) and the sheet is meshed along its rulings, as the
    drawing would be; a designer's facet line without slivers stays."""
    text = (Path(__file__).parent / "data" / "os_export_sliver_facets.fold").read_text()
    exported = pattern_for_folding(parse_fold(text, "export.fold"))
    assert not np.any(exported.assignments == "F")
    assert any("190 facet (F) edge(s) triangulate the faces with corners under 1°" in w for w in exported.warnings)
    run = fold_pattern(exported)
    assert run.report["converged"] and run.report["iterations"] <= 40, run.report["message"]
    plain = json.loads(text)
    del plain["faces_vertices"]  # without faces, the triangles its edges close around the facets tell the same
    bare = pattern_for_folding(parse_fold(json.dumps(plain), "bare.fold"))
    assert not np.any(bare.assignments == "F")
    designed = {  # a facet line the designer drew, with no sliver beside it: kept
        "vertices_coords": [[0, 0], [5, 0], [10, 0], [10, 10], [5, 10], [0, 10]],
        "edges_vertices": [[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [5, 0], [1, 4], [0, 4]],
        "edges_assignment": ["B"] * 6 + ["V", "F"],
        "edges_foldAngle": [0] * 6 + [90, 0],
        "faces_vertices": [[0, 1, 4], [1, 2, 3, 4], [0, 4, 5]],
    }
    kept = pattern_for_folding(parse_fold(json.dumps(designed), "designed.fold"))
    assert np.count_nonzero(kept.assignments == "F") == 1 and not kept.warnings
    del designed["faces_vertices"]
    kept = pattern_for_folding(parse_fold(json.dumps(designed), "designed.fold"))
    assert np.count_nonzero(kept.assignments == "F") == 1 and not kept.warnings


def test_a_crease_pattern_without_fold_angles_folds_flat_foldable() -> None:
    """A crease pattern from Rabbit Ear or ORIPA gives mountains and valleys without ``edges_foldAngle`` (the spec
    makes it optional): they mean flat-foldable creases, −180° and 180°, as Origami Simulator's importer offers.
    They stayed flat before, silently ("converged, 0 iterations"); a null in the array is read the same way. A
    warning says so, and the fold percent scales them."""
    doc = {
        "vertices_coords": [[0, 0], [1, 0], [1, 1], [0, 1], [0.35, 0], [0.35, 1], [0.65, 0], [0.65, 1]],
        "edges_vertices": [[0, 4], [4, 6], [6, 1], [1, 2], [2, 7], [7, 5], [5, 3], [3, 0], [4, 5], [6, 7]],
        "edges_assignment": ["B"] * 8 + ["V", "m"],
        "frame_unit": "cm",
    }
    pattern = pattern_for_folding(parse_fold(json.dumps(doc), "cp.fold"))
    creases = np.isin(pattern.assignments, ("M", "V"))
    assert sorted(pattern.fold_angles[creases].tolist()) == [-180.0, 180.0]
    assert any(
        "2 mountain/valley edge(s) without a fold angle (no edges_foldAngle in the file)" in w for w in pattern.warnings
    )
    run = fold_pattern(pattern, percent=0.5)
    assert run.report["converged"] and run.report["iterations"] > 0
    assert np.ptp(run.result.positions[:, 2]) > 1.0  # folded, not flat (mm: the sheet is 10 mm)
    doc["edges_foldAngle"] = [0] * 8 + [None, -90]
    nulls = pattern_for_folding(parse_fold(json.dumps(doc), "null.fold"))
    assert sorted(nulls.fold_angles[np.isin(nulls.assignments, ("M", "V"))].tolist()) == [-90.0, 180.0]
    assert any("1 mountain/valley edge(s) without a fold angle (null in edges_foldAngle)" in w for w in nulls.warnings)


def test_a_folded_key_frame_reads_its_crease_pattern_from_a_flat_frame() -> None:
    """A FOLD file may keep its folded state in the key frame and the crease pattern in a frame of its own
    (``file_frames`` with ``frame_inherit``, 2D): the pattern is that frame's, the key frame is a folded frame. It
    was refused ("… without a flat crease pattern …"), though the flat pattern was in the file."""
    flat = [[0, 0], [10, 0], [10, 10], [0, 10], [5, 0], [5, 10]]
    folded = [[0, 0, 0], [5, 0, 5], [5, 10, 5], [0, 10, 0], [5, 0, 0], [5, 10, 0]]  # the right half turned up 90°
    doc = {
        "frame_classes": ["foldedForm"],
        "vertices_coords": folded,
        "edges_vertices": [[0, 4], [4, 1], [1, 2], [2, 5], [5, 3], [3, 0], [4, 5]],
        "edges_assignment": ["B", "B", "B", "B", "B", "B", "V"],
        "edges_foldAngle": [0, 0, 0, 0, 0, 0, 90],
        "file_frames": [
            {"frame_classes": ["creasePattern"], "frame_inherit": True, "frame_parent": 0, "vertices_coords": flat}
        ],
    }
    parsed = parse_fold(json.dumps(doc), "key3d.fold")
    np.testing.assert_allclose(parsed.vertices, flat)
    assert len(parsed.frames) == 1 and np.allclose(parsed.frames[0], folded)
    pattern = pattern_for_folding(parsed)
    assert np.count_nonzero(pattern.assignments == "V") == 1


def _plain_fold(pattern, path: Path) -> Path:
    """``pattern`` as another tool writes it: segments only, no ``curved_fold:`` fields."""
    doc = {
        "file_spec": 1.1,
        "frame_unit": "mm",
        "vertices_coords": pattern.vertices.tolist(),
        "edges_vertices": pattern.edges.tolist(),
        "edges_assignment": pattern.assignments.tolist(),
        "edges_foldAngle": [float(a) if np.isfinite(a) else None for a in pattern.fold_angles],
    }
    path.write_text(json.dumps(doc))
    return path


def test_a_plain_fold_files_creases_are_judged_and_named_as_the_strokes_they_draw(tmp_path):
    """Another tool's FOLD file made every edge a crease of its own: the verdict's rule (a crease more than half of
    whose length stays flat or folds the wrong way) was applied per 3–8 mm edge, so the same fold of the same mesh
    was flagged from the FOLD file and not from its SVG twin (a designer's curved hypar: "37 crease(s), 8 %" against
    one crease, 2.8 %; a bent degree-4 vertex at 60 %: flagged against clean), and creases were named by edge.
    Its segments are now chained into strokes (through vertices where two of one role and angle meet, turning by
    30° or less): ``cannot_fold``'s arc is one crease from either file, named by its file edges."""
    svg = REPO / "examples" / "cannot_fold.svg"
    fold = _plain_fold(read_pattern(svg), tmp_path / "cf.fold")
    reports = [fold_pattern(read_pattern(f), percent=1.0).report for f in (svg, fold)]
    for r in reports:
        assert r["does_not_fold_as_assigned"] and len(r["creases_not_folding"]) == 1
    assert reports[1]["crease_length_not_folding_pct"] == pytest.approx(reports[0]["crease_length_not_folding_pct"])
    name = reports[1]["creases_not_folding"][0]["crease"]
    assert name.startswith("cf.fold edges ") and name.endswith(" in one stroke)"), name


def test_drawn_strokes_chain_curves_and_straight_creases_through_crossings_not_corners():
    """A polyline arc (M) crossed by a straight valley drawn as two edges, and a mountain zigzag with a 90° corner:
    the arc is one stroke, the valley one, the zigzag two (a corner is where a drawn stroke ends, as in
    ``flattened_curves``)."""
    from curved_fold.core.pattern.model import CreasePattern
    from curved_fold.core.pattern.polylines import drawn_strokes

    t = np.linspace(0.0, np.pi, 9)
    arc = np.c_[50 + 30 * np.cos(t), 20 + 30 * np.sin(t)]  # vertex 4 is (50, 50): the valley crosses there
    verts = np.r_[arc, [[50.0, 90.0], [50.0, 10.0], [10.0, 80.0], [30.0, 80.0], [30.0, 60.0]]]
    edges = [[k, k + 1] for k in range(8)] + [[4, 9], [4, 10], [11, 12], [12, 13]]
    roles = ["M"] * 8 + ["V", "V", "M", "M"]
    angles = [-90.0] * 8 + [90.0, 90.0, -90.0, -90.0]
    m = len(edges)
    pattern = CreasePattern(
        vertices=verts,
        edges=np.array(edges),
        assignments=np.array(roles),
        fold_angles=np.array(angles),
        edge_polyline=np.arange(m),
        edge_from_curve=np.zeros(m, dtype=bool),
        sources=[f"t.fold edge {k}" for k in range(m)],
    )
    strokes = drawn_strokes(pattern)
    poly = strokes.edge_polyline
    assert len(set(poly[:8].tolist())) == 1 and poly[8] == poly[9] and poly[10] != poly[11]
    assert len(set(poly.tolist())) == 4
    assert strokes.sources[poly[0]] == "t.fold edges 0, 1, … (8 in one stroke)"
    assert strokes.sources[poly[8]] == "t.fold edges 8, 9"
    assert strokes.sources[poly[10]] == "t.fold edge 10"
