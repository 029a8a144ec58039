"""Constrained Delaunay triangulation (core.mesh.triangulate) and the mesh builder (core.mesh.build), on hand-made
patterns, the analytic cases and the Origami Simulator fixtures."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from curved_fold.core.mesh.build import build_mesh
from curved_fold.core.mesh.needles import split_needle_creases
from curved_fold.core.mesh.triangulate import constrained_triangulation
from curved_fold.core.pattern.model import CreasePattern, PatternError
from tests.analytic import bisector_case

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "origami-simulator"
SVGS = sorted(FIXTURES.glob("*.svg"))


def _pattern(vertices, edges, assignments, angles=None) -> CreasePattern:
    m = len(edges)
    angles = [np.nan if a in "BUC" else (0.0 if a == "F" else 90.0) for a in assignments] if angles is None else angles
    return CreasePattern(vertices, edges, list(assignments), angles, list(range(m)), [False] * m)


def _square_with_hole() -> CreasePattern:
    outer = [(0, 0), (10, 0), (10, 10), (0, 10)]
    inner = [(4, 4), (6, 4), (6, 6), (4, 6)]
    edges = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4)]
    return _pattern(outer + inner, edges, "BBBBBBBB")


def _edge_set(tris: np.ndarray) -> set[tuple[int, int]]:
    s = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    return set(map(tuple, s.tolist()))


def _check_mesh(mesh, pattern: CreasePattern | None = None) -> None:
    assert np.all(mesh.signed_areas() > 0), "every triangle counter-clockwise and non-degenerate"
    assert np.all(mesh.edges[:, 0] < mesh.edges[:, 1])
    assert len(np.unique(mesh.edges, axis=0)) == len(mesh.edges)
    assert _edge_set(mesh.triangles) == set(map(tuple, mesh.edges.tolist()))
    diag = mesh.edge_polyline < 0
    assert np.all(mesh.assignments[diag] == "F") and np.all(mesh.fold_angles[diag] == 0)
    assert np.all(np.isnan(mesh.fold_angles[np.isin(mesh.assignments, ("B", "U"))]))
    assert len(mesh.triangle_face) == mesh.n_faces and mesh.triangle_face.max() < len(mesh.faces)
    assert np.unique(mesh.triangles).size == mesh.n_vertices, "no unused vertex"
    if pattern is not None:
        if mesh.mesh_type != "earcut":  # the CDT's pattern: long straight creases split beside needles
            pattern = split_needle_creases(pattern)[0]
        assert np.count_nonzero(mesh.edge_polyline >= 0) == pattern.n_edges + pattern.count("C")


@pytest.mark.parametrize("backend", ["triangle", "mathutils"])
def test_hole_is_removed_and_no_steiner_points(backend: str) -> None:
    pt = constrained_triangulation(_square_with_hole(), backend)
    assert len(pt.vertices) == 8
    assert len(pt.triangles) == 8  # annulus between two quads: 8 vertices, 8 triangles
    centre = np.array([5.0, 5.0])
    v = pt.vertices[pt.triangles]
    bary = v.mean(axis=1)
    assert not np.any(np.all(np.abs(bary - centre) < 1.0, axis=1)), "a triangle inside the hole"
    assert len(pt.faces) == 1 and len(pt.face_loops[0]) == 2 and not pt.face_simple[0]


def test_simple_face_gives_n_minus_2_triangles() -> None:
    # a square split by a V crease: two pentagons... here two faces with 6 and 4 boundary vertices
    verts = [(0, 0), (5, 0), (10, 0), (10, 10), (5, 10), (0, 10), (2, 5), (8, 5)]
    edges = [(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 0), (0, 6), (6, 7), (7, 3)]
    pat = _pattern(verts, edges, "BBBBBBVVV")
    for mesh_type in ("cdt", "earcut", "ruling"):
        mesh = build_mesh(pat, mesh_type)
        _check_mesh(mesh, pat)
        for f, loop in enumerate(mesh.faces):
            assert np.count_nonzero(mesh.triangle_face == f) == len(loop) - 2
        # faces are CCW loops
        for loop in mesh.faces:
            p = mesh.vertices[loop]
            q = np.roll(p, -1, axis=0)
            assert np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]) > 0


def test_dangling_crease_face() -> None:
    verts = [(0, 0), (10, 0), (10, 10), (0, 10), (5, 0), (5, 6)]
    edges = [(0, 4), (4, 1), (1, 2), (2, 3), (3, 0), (4, 5)]
    pat = _pattern(verts, edges, "BBBBBV")
    mesh = build_mesh(pat, "ruling")
    _check_mesh(mesh, pat)
    assert len(mesh.faces) == 1
    assert mesh.n_faces == len(mesh.faces[0]) - 2 == 5  # the walk around the dangling crease has 7 corners
    assert np.count_nonzero(mesh.faces[0] == 4) == 2  # the crease's foot is visited twice around the face


def test_cut_is_split_into_two_border_edges() -> None:
    verts = [(0, 0), (10, 0), (10, 10), (0, 10), (5, 0), (5, 6)]
    edges = [(0, 4), (4, 1), (1, 2), (2, 3), (3, 0), (4, 5)]
    pat = _pattern(verts, edges, "BBBBBC")
    mesh = build_mesh(pat, "cdt")
    _check_mesh(mesh, pat)
    assert mesh.n_vertices == 7  # the cut's foot on the border is duplicated, its tip is not
    assert np.count_nonzero(mesh.assignments == "B") == 5 + 2  # the 5 border segments + both sides of the cut
    assert "C" not in set(mesh.assignments.tolist())


def test_crossing_segments_are_reported() -> None:
    verts = [(0, 0), (10, 0), (10, 10), (0, 10)]
    edges = [(0, 1), (1, 2), (2, 3), (3, 0), (0, 2), (1, 3)]
    pat = _pattern(verts, edges, "BBBBVM")
    for backend in ("triangle", "mathutils"):
        with pytest.raises(PatternError, match="cross"):
            constrained_triangulation(pat, backend)


def _grid_pattern(k: int = 6) -> CreasePattern:
    xs = np.linspace(0, 60, k + 1)
    verts = [(x, y) for y in xs for x in xs]
    idx = np.arange((k + 1) ** 2).reshape(k + 1, k + 1)
    ring = list(idx[0, :]) + list(idx[1:, -1]) + list(idx[-1, -2::-1]) + list(idx[-2:0:-1, 0])
    edges = [(ring[i], ring[(i + 1) % len(ring)]) for i in range(len(ring))]
    edges += [(idx[r, 0], idx[r, 1]) for r in range(1, k)]  # stubs so interior grid points are pattern vertices
    edges += [(idx[r, j], idx[r, j + 1]) for r in range(1, k) for j in range(1, k)]
    a = ["B"] * len(ring) + ["V"] * (len(edges) - len(ring))
    return _pattern(verts, edges, a)


def _circles_pattern() -> CreasePattern:
    verts, edges, a = [], [], []
    for r, asg in ((30.0, "B"), (20.0, "V"), (10.0, "M")):
        base = len(verts)
        th = np.linspace(0, 2 * np.pi, 17)[:-1]
        verts += [(r * np.cos(t), r * np.sin(t)) for t in th]
        edges += [(base + i, base + (i + 1) % 16) for i in range(16)]
        a += [asg] * 16
    return _pattern(verts, edges, a)


@pytest.mark.parametrize("make", [_grid_pattern, _circles_pattern], ids=["grid", "concentric"])
def test_backends_agree_on_cocircular_ties(make) -> None:
    pat = make()
    a = constrained_triangulation(pat, "triangle")
    b = constrained_triangulation(pat, "mathutils")
    assert np.array_equal(a.triangles, b.triangles)
    assert np.array_equal(a.triangle_region, b.triangle_region)
    for mesh_type in ("cdt", "ruling"):
        ma, mb = build_mesh(pat, mesh_type, "triangle"), build_mesh(pat, mesh_type, "mathutils")
        assert np.array_equal(ma.triangles, mb.triangles) and np.array_equal(ma.edges, mb.edges)


def test_bisector_case_mesh_complete() -> None:
    case = bisector_case()
    for mesh_type in ("earcut", "cdt", "ruling"):
        mesh = build_mesh(case.pattern, mesh_type)
        _check_mesh(mesh, case.pattern)
        assert mesh.n_faces == 4 * case.n_segments
        assert mesh.mesh_type == mesh_type and mesh.generation_ms > 0
        crease = mesh.assignments == "V"
        assert np.all(mesh.fold_angles[crease] == 120.0) and np.all(mesh.edge_from_curve[crease])


def _fixture_pattern(path: Path):
    reader = pytest.importorskip("curved_fold.core.io.reader", reason="core.io.reader (INPUT helper) not available")
    return reader.read_pattern(path)


@pytest.mark.parametrize("path", SVGS, ids=[p.name for p in SVGS])
def test_fixtures_mesh_and_backends_agree(path: Path) -> None:
    pat = _fixture_pattern(path)
    for mesh_type in ("earcut", "cdt", "ruling"):
        mesh = build_mesh(pat, mesh_type, "triangle")
        _check_mesh(mesh, pat)
        if mesh_type != "earcut":
            other = build_mesh(pat, mesh_type, "mathutils")
            assert np.array_equal(mesh.triangles, other.triangles), f"{mesh_type} backends differ on {path.name}"


# ------------------------------------------------------------------------------------------ patterns without border


def flaps_svg(n: int = 16, sides: str = "#ff0000") -> str:
    """``n`` curved flaps around an ``n``-gon, drawn with creases only (Origami Simulator's sphere of flaps, in
    kind): each flap's two curved sides (stroke ``sides``) meet at its tip; the polygon's edges are valleys, each
    flap has a mountain spine from the middle of its polygon edge to its tip. Without a border the sides are the
    outer boundary of the drawing."""
    import math

    cx = cy = 75.0
    r0, tip_r = 14.0, 70.0
    body = []
    for k in range(n):
        a0, a1 = 2 * math.pi * k / n, 2 * math.pi * (k + 1) / n
        am = 0.5 * (a0 + a1)
        p0 = (cx + r0 * math.cos(a0), cy + r0 * math.sin(a0))
        p1 = (cx + r0 * math.cos(a1), cy + r0 * math.sin(a1))
        tip = (cx + tip_r * math.cos(am), cy + tip_r * math.sin(am))
        c0 = (cx + 0.55 * tip_r * math.cos(a0 + 0.03), cy + 0.55 * tip_r * math.sin(a0 + 0.03))
        c1 = (cx + 0.55 * tip_r * math.cos(a1 - 0.03), cy + 0.55 * tip_r * math.sin(a1 - 0.03))
        mid = (0.5 * (p0[0] + p1[0]), 0.5 * (p0[1] + p1[1]))
        for d, stroke in (
            (f"M {p0[0]:.5f} {p0[1]:.5f} Q {c0[0]:.5f} {c0[1]:.5f} {tip[0]:.5f} {tip[1]:.5f}", sides),
            (f"M {p1[0]:.5f} {p1[1]:.5f} Q {c1[0]:.5f} {c1[1]:.5f} {tip[0]:.5f} {tip[1]:.5f}", sides),
            (f"M {p0[0]:.5f} {p0[1]:.5f} L {p1[0]:.5f} {p1[1]:.5f}", "#0000ff"),
            (f"M {mid[0]:.5f} {mid[1]:.5f} L {tip[0]:.5f} {tip[1]:.5f}", "#ff0000"),
        ):
            body.append(f'<path d="{d}" fill="none" stroke="{stroke}" opacity="0.25"/>')
    return (
        '<?xml version="1.0" encoding="utf-8"?>\n<svg xmlns="http://www.w3.org/2000/svg" width="150mm" '
        'height="150mm" viewBox="0 0 150 150">\n' + "\n".join(body) + "\n</svg>\n"
    )


def _flaps_pattern(sides: str) -> CreasePattern:
    from curved_fold.core.io.svg import parse_svg_text
    from curved_fold.core.pattern.discretize import discretize

    return discretize(parse_svg_text(flaps_svg(sides=sides), "flaps.svg").curves)


def test_an_outline_drawn_as_cuts_is_not_said_to_stop_folding() -> None:
    """Flaps whose sides are drawn as cuts (green), no border: the sides become the border as with creases, but the
    warning does not say that cuts "no longer fold" (they never folded); it says they are all cuts."""
    cut = build_mesh(_flaps_pattern("#00ff00"), "ruling")
    said = [w for w in cut.warnings if "took the outer boundary" in w]
    assert len(said) == 1 and said[0].endswith(", all cuts)") and "no longer fold" not in said[0], said


def _by_position(mesh, values: np.ndarray) -> np.ndarray:
    order = np.lexsort(mesh.vertices.T[::-1])
    return values[order]


def test_pattern_without_border_takes_the_outer_boundary_as_border() -> None:
    """Issue 12 item 5: sixteen flaps drawn with creases only mesh exactly as the same drawing with the flap sides
    drawn as border: the same vertices, the same border edges, the same faces; the warning says what was done."""
    bare = build_mesh(_flaps_pattern("#ff0000"), "ruling")
    drawn = build_mesh(_flaps_pattern("#000000"), "ruling")
    assert any("no border (B) segments drawn: took the outer boundary" in w for w in bare.warnings)
    assert any(re.search(r"the \d+ crease segment\(s\) among them no longer fold\)$", w) for w in bare.warnings)
    assert not any("outer boundary" in w for w in drawn.warnings)
    assert bare.n_vertices == drawn.n_vertices and bare.n_faces == drawn.n_faces
    assert np.allclose(_by_position(bare, bare.vertices), _by_position(drawn, drawn.vertices))

    def border_set(mesh) -> set:
        e = mesh.edges[mesh.assignments == "B"]
        return {tuple(sorted(map(tuple, np.round(mesh.vertices[pair], 6).tolist()))) for pair in e}

    assert border_set(bare) == border_set(drawn)
    assert len(border_set(bare)) > 16 * 2  # both curved sides of every flap, several pieces each
    crease = {a: int(np.count_nonzero(bare.assignments == a)) for a in "MV"}
    assert crease == {a: int(np.count_nonzero(drawn.assignments == a)) for a in "MV"}
    assert crease["V"] == 32 and crease["M"] == 16  # polygon edges split by the spines; one spine per flap


def test_pattern_without_border_folds() -> None:
    """The borderless flaps fold (to the same state as with the border drawn), converged."""
    from curved_fold.core.pipeline import fold_pattern

    bare = fold_pattern(_flaps_pattern("#ff0000"), percent=0.6)
    drawn = fold_pattern(_flaps_pattern("#000000"), percent=0.6)
    assert bare.report["converged"] and drawn.report["converged"]
    pb = _by_position(bare.mesh, bare.result.positions)
    pd = _by_position(drawn.mesh, drawn.result.positions)
    assert np.abs(pb - pd).max() <= 1e-6 * bare.mesh.diagonal
    assert np.ptp(pb[:, 2]) > 10.0  # the flaps rise out of the plane


@pytest.mark.parametrize(
    "body",
    [
        '<path d="M0 50 L100 50" stroke="#f00"/><path d="M50 0 L50 100" stroke="#00f"/>',  # a cross: no region
        '<path d="M50 0 L50 100" stroke="#f00"/>',  # one line
    ],
    ids=["cross", "line"],
)
def test_pattern_without_border_enclosing_nothing_is_refused_in_one_line(body: str) -> None:
    from curved_fold.core.io.svg import parse_svg_text
    from curved_fold.core.pattern.discretize import discretize

    svg = f'<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100">{body}</svg>'
    pattern = discretize(parse_svg_text(svg, "t.svg").curves)
    with pytest.raises(PatternError, match=r"crease pattern has no border \(B\) segments: .* enclose no region"):
        build_mesh(pattern, "ruling")


def _fuzz_flip_cycle_pattern():
    """A fuzzed pattern (tools/fuzz_long.py, seed 1, 1,000 examples): a Bézier border and two straight creases
    that cross it, whose near-cocircular nodes made the tolerance's Lawson flips go round a cycle."""
    from curved_fold.core.pattern.discretize import discretize
    from curved_fold.core.pattern.model import CreaseCurve, CurveSegment

    border = [
        [[84.2148580368414, 118.9122796333025], [57.51515402256985, 100.52975845955464]],
        [[32.78451530976501, 79.79832830077599], [10.022941898426893, 56.71798915696655]],
        [[47.10728616402053, 46.43184651791864], [84.19162859030735, 36.14569724767356]],
        [[121.27596917728735, 25.859541346231303], [114.79492769119412, 42.240881494147594]],
        [[108.31088690952875, 58.621034378737164], [101.82384683229127, 75.00000000000001]],
        [[114.21958089028098, 96.96191922902756], [108.34991795846436, 111.59934577346172]],
    ]
    pts = [p for pair in border for p in pair] + [border[0][0]]
    segs = [CurveSegment("cubic", np.array(pts[3 * k : 3 * k + 4], dtype=float)) for k in range(4)]
    line = lambda a, b: [CurveSegment("line", np.array([a, b], dtype=float))]  # noqa: E731
    return discretize(
        [
            CreaseCurve(segs, "B", None, closed=True, source="fuzz border (bezier)"),
            CreaseCurve(line([-14.9982, 89.99554032166103], [75.40244615960847, -11.820838252027901]), "M", -102.9),
            CreaseCurve(line([19.808598421852455, 9.017779105111774], [152.67962865055426, -14.982]), "V", -2.54),
        ]
    )


def test_delaunay_flips_that_cycle_under_the_tolerance_are_redone_exactly(monkeypatch) -> None:
    """The tolerance's flips cycle on this input (they raised "Delaunay legalisation did not terminate", a
    RuntimeError that reached the user); the pass is redone with exact predicates: it terminates, and every edge
    that is not a segment is then locally Delaunay exactly."""
    from fractions import Fraction

    from curved_fold.core.mesh import triangulate as tr

    seen = []
    real = tr.legalise
    monkeypatch.setattr(tr, "legalise", lambda *args: seen.append(args) or real(*args))
    mesh = build_mesh(_fuzz_flip_cycle_pattern(), mesh_type="cdt")
    assert mesh.n_faces > 0
    points, tris, constrained = seen[0]
    with pytest.raises(tr._FlipCycleError):
        tr._lawson(points, tris, constrained, exact=False)
    out, _ = tr.legalise(points, tris, constrained)
    fr = [(Fraction(x), Fraction(y)) for x, y in points.tolist()]
    owner = {(int(t[k]), int(t[(k + 1) % 3])): int(t[(k + 2) % 3]) for t in out for k in range(3)}
    for (a, b), c in owner.items():
        d = owner.get((b, a))
        if d is None or (min(a, b), max(a, b)) in constrained:
            continue
        val = tr._incircle_exact(fr[a], fr[b], fr[c], fr[d])
        assert val < 0 or (val == 0 and min(c, d) > min(a, b)), (a, b)


def test_an_isolated_vertex_is_dropped_and_said_where() -> None:
    """A FOLD file may list a vertex no edge uses: it is dropped with a warning that says where it is (it gave only
    a count, and a file's vertex index no longer matches the pattern's after merges)."""
    p = _pattern(
        np.array([[0, 0], [10, 0], [10, 10], [0, 10], [4, 0], [4, 10], [7.5, 2.5]], float),
        np.array([[0, 4], [4, 1], [1, 2], [2, 5], [5, 3], [3, 0], [4, 5]]),
        "BBBBBBV",
    )
    pt = constrained_triangulation(p)
    assert "triangulation: 1 isolated vertex(es) without segments dropped, at (7.500, 2.500) mm" in pt.warnings
