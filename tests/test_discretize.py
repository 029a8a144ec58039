"""Discretisation (paper §3.1) and the planar clean-up: measured accuracy, splitting, merging, fixtures."""

from __future__ import annotations

import itertools
import math
import time
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from curved_fold.core.io.svg import parse_svg_text, read_svg
from curved_fold.core.pattern.discretize import (
    MAX_SEGMENTS,
    curve_parameters,
    default_parameters,
    discretize,
    discretize_steps,
    sheet_size,
)
from curved_fold.core.pattern.model import CreaseCurve, CurveSegment, PatternError
from curved_fold.core.pattern.polylines import flattened_curves
from curved_fold.core.pipeline import fold_pattern

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "origami-simulator"
FIXTURE_FILES = sorted(FIXTURES.glob("*.svg")) if FIXTURES.is_dir() else []
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def line(a, b) -> CurveSegment:
    return CurveSegment("line", np.array([a, b], dtype=float))


def square(size: float = 100.0) -> CreaseCurve:
    c = [(0, 0), (size, 0), (size, size), (0, size)]
    return CreaseCurve([line(c[i], c[(i + 1) % 4]) for i in range(4)], "B", None, closed=True, source="square")


def circle(r: float, centre=(0.0, 0.0), assignment: str = "M") -> CreaseCurve:
    cx, cy = centre
    segs = [
        CurveSegment("arc", np.array([[cx + r, cy], [cx - r, cy]]), (cx, cy, r, r, 0.0, 0.0, math.pi)),
        CurveSegment("arc", np.array([[cx - r, cy], [cx + r, cy]]), (cx, cy, r, r, 0.0, math.pi, math.pi)),
    ]
    return CreaseCurve(segs, assignment, -90.0 if assignment == "M" else None, closed=True, source=f"circle r={r}")


def chords(pattern) -> tuple[np.ndarray, np.ndarray]:
    return pattern.vertices[pattern.edges[:, 0]], pattern.vertices[pattern.edges[:, 1]]


# ------------------------------------------------------------------------------------------------ accuracy


@pytest.mark.parametrize(
    "r,interval,tol", [(50.0, 7.0, 0.07), (10.0, 7.0, 0.01), (200.0, 20.0, 0.5), (3.0, 1.0, 0.001)]
)
def test_circle_chords_stay_within_tolerance_and_interval(r: float, interval: float, tol: float) -> None:
    p = discretize([circle(r)], interval=interval, tolerance=tol, merge_tolerance=tol / 10)
    a, b = chords(p)
    lengths = np.hypot(*(b - a).T)
    assert lengths.max() <= interval * (1 + 1e-9)
    s = np.linspace(0.0, 1.0, 101)[None, :, None]
    dense = a[:, None, :] * (1 - s) + b[:, None, :] * s  # 101 points along every chord
    deviation = r - np.hypot(dense[..., 0], dense[..., 1])
    assert deviation.max() <= tol * (1 + 1e-9)
    assert np.abs(np.hypot(*p.vertices.T) - r).max() < 1e-9  # vertices on the circle
    # the loop is closed: every vertex has degree 2
    assert np.all(np.bincount(p.edges.ravel()) == 2)
    assert p.edge_from_curve.all() and set(p.assignments) == {"M"}
    assert np.all(p.fold_angles == -90.0)


def test_equal_parameter_count_is_the_smallest_and_refinement_meets_tolerance() -> None:
    seg = CurveSegment("cubic", np.array([[0, 0], [10, 60], [90, -60], [100, 0]], dtype=float))
    interval = 9.0
    t = curve_parameters(seg, interval, tolerance=1e9)  # tolerance never binds: equal steps only
    n = len(t) - 1
    np.testing.assert_allclose(np.diff(t), 1.0 / n)
    assert np.hypot(*np.diff(seg.evaluate(t), axis=0).T).max() <= interval
    fewer = seg.evaluate(np.linspace(0, 1, n))
    assert np.hypot(*np.diff(fewer, axis=0).T).max() > interval  # n - 1 steps would not do
    t2 = curve_parameters(seg, interval, tolerance=0.05)
    assert set(np.round(t, 12)) <= set(np.round(t2, 12))  # refinement only inserts
    p = seg.evaluate(t2)
    mid = seg.evaluate(0.5 * (t2[:-1] + t2[1:]))
    ab = p[1:] - p[:-1]
    u = np.clip(np.einsum("ij,ij->i", mid - p[:-1], ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
    dist = np.hypot(*(mid - (p[:-1] + u[:, None] * ab)).T)
    assert dist.max() <= 0.05 and len(t2) > len(t)


def test_default_parameters_are_scale_aware() -> None:
    assert default_parameters(150.0) == pytest.approx((7.0, 0.07, 0.05))
    assert default_parameters(300.0) == pytest.approx((14.0, 0.14, 0.1))
    with pytest.raises(PatternError):
        default_parameters(0.0)
    small = discretize([square(100.0), circle(30.0, (50, 50))])
    big = discretize([square(1000.0), circle(300.0, (500, 500))])
    assert small.n_edges == big.n_edges and small.n_vertices == big.n_vertices
    np.testing.assert_allclose(big.vertices, small.vertices * 10, atol=1e-9)


def test_sheet_size_uses_the_border() -> None:
    assert sheet_size([square(80.0), circle(200.0, (40, 40))]) == pytest.approx(80.0)
    assert sheet_size([circle(20.0)]) == pytest.approx(40.0, rel=1e-3)


# ------------------------------------------------------------------------------------------------ straight parts


def test_border_split_evenly_straight_creases_and_polylines_kept() -> None:
    border = square(100.0)
    crease = CreaseCurve([line((0, 50), (100, 50))], "V", 90.0, source="crease")
    poly_pts = [(10, 10), (30, 10.001), (50, 10), (70, 10.002), (90, 10)]  # nearly collinear: must stay
    poly = CreaseCurve([line(poly_pts[i], poly_pts[i + 1]) for i in range(4)], "M", -90.0, source="poly")
    p = discretize([border, crease, poly], interval=7.0, tolerance=0.07, merge_tolerance=0.0001)
    border_lengths = np.hypot(*np.subtract(*chords(p)).T)[p.assignments == "B"]
    # each 100 mm side: ceil(100/7) = 15 pieces, but the crease's T-junctions split two of them once more
    assert p.count("B") == 4 * 15 + 2
    assert border_lengths.max() <= 7.0
    assert p.count("V") == 1 and p.count("M") == 4
    assert not p.edge_from_curve.any()
    for q in poly_pts:
        assert np.min(np.hypot(*(p.vertices - q).T)) < 1e-12


def test_x_crossing_and_t_junction_are_split() -> None:
    a = CreaseCurve([line((0, 0), (10, 10))], "M", -90.0, source="a")
    b = CreaseCurve([line((0, 10), (10, 0))], "V", 90.0, source="b")
    t = CreaseCurve([line((5, 5), (5, -3))], "F", 0.0, source="t")  # starts on the crossing point
    u = CreaseCurve([line((2, 8), (-4, 8))], "U", None, source="u")  # T onto b at (2, 8)
    p = discretize([a, b, t, u], interval=100, tolerance=1, merge_tolerance=1e-6)
    assert Counter(p.assignments.tolist()) == {"M": 2, "V": 3, "F": 1, "U": 1}
    centre = np.flatnonzero(np.hypot(*(p.vertices - (5, 5)).T) < 1e-9)
    assert len(centre) == 1 and np.count_nonzero(p.edges == centre[0]) == 5
    assert np.min(np.hypot(*(p.vertices - (2, 8)).T)) < 1e-9
    assert {p.sources[k] for k in p.edge_polyline.tolist()} == {"a", "b", "t", "u"}


def test_collinear_overlap_and_duplicates_keep_the_border_and_warn() -> None:
    border = square(10.0)
    on_border = CreaseCurve([line((2, 0), (5, 0))], "M", -90.0, source="red on border")
    twice = CreaseCurve([line((1, 1), (9, 9))], "V", 90.0, source="valley")
    again = CreaseCurve([line((9, 9), (1, 1))], "F", 0.0, source="facet copy")
    p = discretize([border, on_border, twice, again], interval=100, tolerance=1, merge_tolerance=1e-6)
    assert p.count("M") == 0 and p.count("F") == 0 and p.count("V") == 1
    # the outline whole, where it was drawn (the vertices the dropped crease left at x = 2 and 5 on the bottom side
    # are no junction: a straight chain sampled that much finer than the interval is thinned)
    b = p.edges[p.assignments == "B"]
    assert np.isclose(np.hypot(*(p.vertices[b[:, 1]] - p.vertices[b[:, 0]]).T).sum(), 40.0)
    assert {(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)} <= set(map(tuple, p.vertices[np.unique(b)].tolist()))
    text = " ".join(p.warnings)
    assert "kept square (B) over red on border (M)" in text and "kept valley (V) over facet copy (F)" in text


def test_close_vertices_merge_and_zero_length_segments_vanish() -> None:
    a = CreaseCurve([line((0, 0), (10, 0))], "M", -90.0, source="a")
    b = CreaseCurve([line((10.004, 0.003), (10, 10))], "V", 90.0, source="b")
    z = CreaseCurve([line((3, 3), (3, 3))], "V", 90.0, source="zero")
    p = discretize([a, b, z], interval=100, tolerance=1, merge_tolerance=0.01)
    assert p.n_edges == 2 and p.n_vertices == 3
    np.testing.assert_allclose(p.vertices[np.bincount(p.edges.ravel()) == 2][0], (10, 0))  # first one kept


def test_crease_crossing_the_border_is_trimmed_with_a_warning() -> None:
    crease = CreaseCurve([line((50, -2), (50, 102))], "V", 90.0, source="long crease")
    p = discretize([square(100.0), crease], interval=10, tolerance=0.1, merge_tolerance=1e-4)
    v = p.vertices[p.edges[p.assignments == "V"]]
    assert p.count("V") == 1 and v[:, :, 1].min() == pytest.approx(0) and v[:, :, 1].max() == pytest.approx(100)
    assert any("removed 2 crease segment(s) outside the border, from long crease" in w for w in p.warnings)


def test_border_open_at_one_place_is_closed_with_a_straight_edge() -> None:
    b = CreaseCurve([line((0, 0), (10, 0)), line((10, 0), (10, 10))], "B", None, source="half")
    p = discretize([b], interval=100, tolerance=1)
    assert any(
        "the border is not closed (half): joined its loose ends at (0.000, 0.000) and (10.000, 10.000) mm with a "
        "straight edge, 14.14 mm long" in w
        for w in p.warnings
    ), p.warnings
    degree = np.bincount(p.edges[p.assignments == "B"].ravel(), minlength=p.n_vertices)
    assert set(degree[degree > 0].tolist()) == {2}  # one closed loop


def test_border_open_at_several_places_is_reported() -> None:
    sides = [
        CreaseCurve([line((0, 0), (10, 0))], "B", None, source="bottom"),
        CreaseCurve([line((10, 1), (10, 10)), line((10, 10), (0, 10))], "B", None, source="right and top"),
    ]
    p = discretize(sides, interval=100, tolerance=1)
    assert any("border is not closed: 4 loose end(s)" in w for w in p.warnings), p.warnings
    assert not any("joined its loose ends" in w for w in p.warnings)


def _one_loop(p) -> bool:
    degree = np.bincount(p.edges[p.assignments == "B"].ravel(), minlength=p.n_vertices)
    return set(degree[degree > 0].tolist()) == {2}


def test_border_pieces_that_miss_at_several_corners_by_a_hair_are_joined() -> None:
    """A 150 mm square drawn as four lines that miss each other by 0.1 mm at every corner (a designer session, in
    Blender and as SVG <line>s): left open, two such gaps folded nothing ("converged" in 0 iterations, no crease
    with paper on both sides) and four gave "no paper left". Each pair of loose ends that are each other's nearest,
    within 1 % of the sheet, is joined: at the corner where the two pieces' lines meet (a straight edge between the
    ends cut a chamfer off it, and a crease drawn to the corner ended outside the sheet), or by a straight edge
    where the pieces run on nearly straight (a border drawn in two strokes that miss mid-side)."""
    sides = [
        CreaseCurve([line((0.1, 0), (150, 0))], "B", None, source="bottom"),
        CreaseCurve([line((150, 0.1), (150, 150))], "B", None, source="right"),
        CreaseCurve([line((149.9, 150), (0, 150))], "B", None, source="top"),
        CreaseCurve([line((0, 149.9), (0, 0.1))], "B", None, source="left"),
    ]
    crease = CreaseCurve([line((0, 0), (150, 150))], "V", 90.0, source="diagonal")
    p = discretize([*sides, crease])
    assert _one_loop(p)
    said = [w for w in p.warnings if "not closed" in w]
    assert len(said) == 1 and said[0].startswith("the border is not closed at 4 place(s) (")
    assert "): 4 drawn on to the corner where their lines meet (up to 0.1 mm), at " in said[0]
    outline = {tuple(np.round(p.vertices[v], 9)) for v in p.edges[p.assignments == "B"].ravel()}
    assert {(0.0, 0.0), (150.0, 0.0), (150.0, 150.0), (0.0, 150.0)} <= outline  # the corners, not chamfers
    diagonal = p.edges[p.assignments == "V"]
    assert {tuple(np.round(p.vertices[v], 9)) for v in np.unique(diagonal)} >= {(0.0, 0.0), (150.0, 150.0)}
    run = fold_pattern(p, percent=0.5)
    assert run.result.converged and run.report["crease_length_not_folding_pct"] == 0
    # one side drawn to the corner (0.02 mm off it, within the merge tolerance), the next 0.5 mm short of it: the
    # corner is that side's end, joined straight (a zero-length edge made it "cross itself" there, refused)
    sloppy = [
        CreaseCurve([line((0, 0), (99.5, 0))], "B", None),
        CreaseCurve([line((100, 0.02), (100, 100))], "B", None),
        CreaseCurve([line((100, 100), (0.5, 100))], "B", None),
        CreaseCurve([line((0, 99.5), (0, 0))], "B", None),
        CreaseCurve([line((0, 0), (100, 100))], "M", 90.0),
    ]
    p = discretize(sloppy)
    assert _one_loop(p) and fold_pattern(p, percent=0.5).result.converged
    # a crease drawn 3 mm past a corner the outline misses: split where it crosses the joined corner and trimmed
    # there (it crossed the join with no vertex on it, and the triangulation refused "edges … cross or touch")
    past = [
        CreaseCurve([line((0, 0), (99.5, 0))], "B", None),
        CreaseCurve([line((100, 0.5), (100, 100))], "B", None),
        CreaseCurve([line((100, 100), (0, 100))], "B", None),
        CreaseCurve([line((0, 99.5), (0, 0.5))], "B", None),
        CreaseCurve([line((0, 100), (103, -3))], "M", 90.0),
    ]
    p = discretize(past)
    assert any(w.startswith("removed 1 crease segment(s) outside the border") for w in p.warnings), p.warnings
    creased = {tuple(np.round(p.vertices[v], 9)) for v in np.unique(p.edges[p.assignments == "M"])}
    assert (100.0, 0.0) in creased and _one_loop(p) and fold_pattern(p, percent=0.5).result.converged
    # two strokes that miss each other mid-side, running on straight (joined by a straight edge), and at a corner
    halves = [
        CreaseCurve([line((0, 0), (150, 0)), line((150, 0), (150, 150)), line((150, 150), (75.2, 150))], "B", None),
        CreaseCurve([line((74.9, 150), (0, 150)), line((0, 150), (0, 0.2))], "B", None),
    ]
    [said] = [w for w in discretize(halves).warnings if "not closed" in w]
    assert "): 1 drawn on to the corner where their lines meet (up to 0.2 mm); 1 joined by a straight edge (up " in said


def test_an_outline_open_at_one_corner_is_drawn_on_to_the_corner() -> None:
    """A square whose bottom stops 0.5 mm short of a corner and whose right side starts 0.5 mm above it, with a crease
    drawn to that corner: the one gap was closed by a straight edge between the ends, a chamfer that left the
    crease's end outside the sheet (cut back, 0.35 mm from the corner). Both ends are drawn on to the corner now; a
    gap whose one end is at the corner already is closed by the straight edge along the side, as before."""
    sides = [
        CreaseCurve([line((0, 0), (99.5, 0))], "B", None, source="bottom"),
        CreaseCurve([line((100, 0.5), (100, 100)), line((100, 100), (0, 100)), line((0, 100), (0, 0))], "B", None),
        CreaseCurve([line((0, 100), (100, 0))], "M", 90.0, source="diagonal"),
    ]
    p = discretize(sides)
    [said] = [w for w in p.warnings if "not closed" in w]
    assert "on to the corner where their lines meet, (100.000, 0.000) mm, up to 0.5 mm" in said
    assert not any("outside the border" in w for w in p.warnings)
    assert _one_loop(p)
    diagonal = np.unique(p.edges[p.assignments == "M"])
    assert (100.0, 0.0) in {tuple(np.round(p.vertices[v], 9)) for v in diagonal}  # the crease reaches the corner
    mid = [
        CreaseCurve(
            [line((0, 0), (60, 0)), line((60, 0), (60, 60)), line((60, 60), (0, 60)), line((0, 60), (0, 0.4))],
            "B",
            None,
        )
    ]
    [said] = [w for w in discretize(mid).warnings if "not closed" in w]
    assert "with a straight edge, 0.4 mm long" in said


def test_slits_drawn_in_black_keep_their_bridges_and_an_outline_missing_its_start_closes() -> None:
    """A review session's kirigami sheets: a square outline of four lines meeting at the corners, and black slits
    with 1 mm paper bridges between them. Joining loose ends in pairs before the planar clean-up closed the bridges
    and the sheet fell apart; the slits are cuts, their bridges stay. And an outline drawn as one stroke whose last
    point lands 0.3 mm beside its start (nearer its first side than its start) is closed, as it was."""
    sides = [
        CreaseCurve([line((0, 0), (150, 0))], "B", None, source="bottom"),
        CreaseCurve([line((150, 0), (150, 150))], "B", None, source="right"),
        CreaseCurve([line((150, 150), (0, 150))], "B", None, source="top"),
        CreaseCurve([line((0, 150), (0, 0))], "B", None, source="left"),
    ]
    slits = [
        CreaseCurve([line((0, 75), (74.5, 75))], "B", None, source="slit a"),
        CreaseCurve([line((75.5, 75), (150, 75))], "B", None, source="slit b"),
    ]
    crease = CreaseCurve([line((55, 0), (55, 150))], "V", 90.0, source="valley")
    p = discretize([*sides, *slits, crease])
    assert not any("not closed" in w for w in p.warnings), p.warnings
    assert p.count("C") >= 2 and any("read as cuts" in w for w in p.warnings)
    assert fold_pattern(p, percent=0.5).report["converged"]
    outline = CreaseCurve(
        [line((0, 0), (150, 0)), line((150, 0), (150, 150)), line((150, 150), (0, 150)), line((0, 150), (0.4, 0.3))],
        "B",
        None,
        source="outline",
    )
    p = discretize([outline, crease])
    assert _one_loop(p) and any(w.startswith("the border is not closed (outline): joined") for w in p.warnings)


def test_border_drawn_past_its_corners_is_trimmed() -> None:
    """Four border lines drawn 0.3 mm past the corners of a 150 mm square (by eye, or a CAD program's lines) crossed
    each other at every corner and the pattern was refused ("the border crosses or touches itself"); a stroke drawn
    past its own start was closed with a chord along itself and then reported open. Stubs of the border up to 1 %
    of the sheet beyond where it meets itself are trimmed, with one warning."""
    sides = [
        CreaseCurve([line((-0.3, 0), (150.3, 0))], "B", None, source="bottom"),
        CreaseCurve([line((150, -0.3), (150, 150.3))], "B", None, source="right"),
        CreaseCurve([line((150.3, 150), (-0.3, 150))], "B", None, source="top"),
        CreaseCurve([line((0, 150.3), (0, -0.3))], "B", None, source="left"),
    ]
    crease = CreaseCurve([line((0, 0), (150, 150))], "V", 90.0, source="diagonal")
    p = discretize([*sides, crease])
    assert _one_loop(p) and p.vertices.min() == 0.0 and p.vertices.max() == 150.0
    assert [w for w in p.warnings if "border" in w] == [
        "trimmed 8 border stub(s) drawn past where the outline meets itself, up to 0.3 mm long, from bottom, right, "
        "top, left"
    ]
    past = CreaseCurve(
        [line((0, 0), (150, 0)), line((150, 0), (150, 150)), line((150, 150), (0, 150)), line((0, 150), (0, -0.5))],
        "B",
        None,
        source="outline",
    )
    p = discretize([past, crease])
    assert _one_loop(p)
    assert [w for w in p.warnings if "border" in w] == [
        "trimmed 1 border stub(s) drawn past where the outline meets itself, up to 0.5 mm long, from outline"
    ]
    # 3 mm past (2 % of the sheet): refused, saying where and by how much (it said to draw one loop)
    far = [
        CreaseCurve([line((-3, 0), (153, 0))], "B", None, source="bottom"),
        CreaseCurve([line((150, -3), (150, 153))], "B", None, source="right"),
        CreaseCurve([line((153, 150), (-3, 150))], "B", None, source="top"),
        CreaseCurve([line((0, 153), (0, -3))], "B", None, source="left"),
    ]
    with pytest.raises(PatternError, match=r"drawn on past itself by 3 mm at \(.*\) mm, more than 1 % of the sheet"):
        discretize([*far, crease])


@pytest.mark.slow
def test_explosion_is_capped_with_a_warning() -> None:
    t0 = time.perf_counter()
    p = discretize([circle(100.0)], interval=0.0001, tolerance=1.0)
    assert p.n_edges <= MAX_SEGMENTS * 1.05
    assert any("discretisation capped" in w and "interval 0.0001 mm" in w for w in p.warnings)
    assert time.perf_counter() - t0 < 30


def test_bad_parameters_and_input() -> None:
    with pytest.raises(PatternError, match="interval"):
        discretize([square()], interval=-1)
    with pytest.raises(PatternError, match="tolerance"):
        discretize([square()], tolerance=0)
    with pytest.raises(PatternError, match="no curves"):
        discretize([])
    bad = CreaseCurve([line((0, 0), (np.nan, 1))], "M", -90.0, source="SVG <line> (line 7)")
    with pytest.raises(PatternError, match=r"SVG <line> \(line 7\): non-finite"):
        discretize([square(), bad])


# ------------------------------------------------------------------------------------------------ fixtures


@pytest.mark.parametrize("path", FIXTURE_FILES, ids=lambda p: p.name)
def test_every_fixture_discretises(path: Path) -> None:
    drawing = read_svg(path)
    t0 = time.perf_counter()
    p = discretize(drawing.curves)
    ms = (time.perf_counter() - t0) * 1e3
    p.validate()
    assert ms < 5000
    counts = Counter(c.assignment for c in drawing.curves)
    assert set(p.assignments.tolist()) == set(counts)
    lengths = np.hypot(*np.subtract(*chords(p)).T)
    _, _, merge = default_parameters(sheet_size(drawing.curves))
    # no drawn element is lost: a curve without pieces of its own was an exact duplicate of an existing edge
    have = set(p.edge_polyline.tolist())
    edge_set = {tuple(e) for e in np.sort(p.edges, axis=1).tolist()}
    for k, c in enumerate(drawing.curves):
        if k in have:
            continue
        assert len(c.segments) == 1 and c.segments[0].is_straight, c.source
        ends = [
            int(np.argmin(np.hypot(*(p.vertices - q).T))) for q in (c.segments[0].points[0], c.segments[0].points[-1])
        ]
        assert tuple(sorted(ends)) in edge_set, c.source
    assert lengths.min() >= merge
    assert len(np.unique(np.sort(p.edges, axis=1), axis=0)) == p.n_edges  # no duplicates
    assert p.edge_from_curve.any() == any(c.is_curved for c in drawing.curves)
    assert not any("not closed" in w for w in p.warnings), p.warnings
    # curve pieces are never longer than the interval
    interval, _, _ = default_parameters(sheet_size(drawing.curves))
    assert lengths[p.edge_from_curve].max(initial=0) <= interval * (1 + 1e-9)


def test_discretisation_in_units_gives_the_same_pattern_and_each_unit_is_short() -> None:
    """A Blender job runs ``discretize_steps`` one unit per slice: on the 3,000-segment CircularPleat-antiFacet
    the units return the same pattern as ``discretize`` (their times are in docs/benchmarks.md)."""
    curves = read_svg(FIXTURES / "CircularPleat-antiFacet.svg").curves
    whole = discretize(curves)
    steps = discretize_steps(curves)
    names = list(itertools.islice(steps, 4))
    with pytest.raises(StopIteration) as done:
        next(steps)
    units = done.value.value
    assert names == ["parameters", "curves sampled", "planar arrangement", "clipped to the border"]
    np.testing.assert_array_equal(units.vertices, whole.vertices)
    np.testing.assert_array_equal(units.edges, whole.edges)
    np.testing.assert_array_equal(units.assignments, whole.assignments)
    assert units.warnings == whole.warnings


def test_treble_clef_curved_border_is_one_closed_polyline() -> None:
    p = discretize(read_svg(FIXTURES / "Treble_Clef.svg").curves)
    border = p.edges[p.assignments == "B"]
    assert len(border) > 100 and p.edge_from_curve[p.assignments == "B"].any()
    deg = np.bincount(border.ravel(), minlength=p.n_vertices)
    assert set(deg[np.unique(border)].tolist()) == {2}
    # walk the loop: it visits every border vertex once and returns to the start
    nbrs: dict[int, list[int]] = {}
    for i, j in border.tolist():
        nbrs.setdefault(i, []).append(j)
        nbrs.setdefault(j, []).append(i)
    start = border[0, 0]
    prev, cur, steps = start, nbrs[start][0], 1
    while cur != start:
        prev, cur = cur, next(x for x in nbrs[cur] if x != prev)
        steps += 1
    assert steps == len(border) == len(nbrs)
    # the mountain ends on the border: both ends of its polyline are border vertices
    m = p.edges[p.assignments == "M"]
    ends = np.flatnonzero(np.bincount(m.ravel(), minlength=p.n_vertices) == 1)
    assert len(ends) == 2 and all(deg[e] == 2 for e in ends)


def test_circular_pleat_radial_facets_split_at_ring_vertices() -> None:
    p = discretize(read_svg(FIXTURES / "CircularPleat-antiFacet.svg").curves)
    assert p.n_vertices == 1600 and p.count("M") == 700 and p.count("V") == 700 and p.count("B") == 200
    assert p.count("F") == 3000  # 1500 ring diagonals + 100 radial lines through 15 ring vertices each


def test_examples_end_on_the_border() -> None:
    files = sorted(EXAMPLES.glob("*.svg"))
    assert {f.name for f in files} >= {
        "single_curve.svg",
        "curved_pleats.svg",
        "concentric_arcs.svg",
        "curved_border.svg",
        "cannot_fold.svg",
    }
    for f in files:
        drawing = read_svg(f)
        assert drawing.width_mm == pytest.approx(150.0)
        p = discretize(drawing.curves)
        assert not p.warnings, (f.name, p.warnings)
        creases = p.edges[np.isin(p.assignments, ["M", "V"])]
        deg = np.bincount(creases.ravel(), minlength=p.n_vertices)
        border_deg = np.bincount(p.edges[p.assignments == "B"].ravel(), minlength=p.n_vertices)
        assert np.all(border_deg[deg == 1] == 2), f.name  # every crease end is a border vertex


def test_example_fold_angles() -> None:
    p = discretize(read_svg(EXAMPLES / "single_curve.svg").curves)
    assert set(p.fold_angles[p.assignments == "V"].round(9).tolist()) == {108.0}
    q = discretize(read_svg(EXAMPLES / "cannot_fold.svg").curves)
    assert q.count("V") == 0 and q.count("M") > 0
    r = discretize(read_svg(EXAMPLES / "concentric_arcs.svg").curves)
    assert r.count("V") > 0 and r.count("M") > 0


def test_arc_crease_between_points_of_a_circular_border() -> None:
    text = (
        '<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100">'
        '<circle cx="50" cy="50" r="45" stroke="black"/><path d="M5 50 A 60 60 0 0 1 95 50" stroke="blue"/></svg>'
    )
    p = discretize(parse_svg_text(text, "c.svg").curves)
    assert p.count("V") > 5 and not p.warnings
    assert p.edge_from_curve.all()
    v = p.edges[p.assignments == "V"]
    ends = np.flatnonzero(np.bincount(v.ravel(), minlength=p.n_vertices) == 1)
    np.testing.assert_allclose(sorted(p.vertices[ends].tolist()), [[5, -50], [95, -50]], atol=1e-9)
    border_deg = np.bincount(p.edges[p.assignments == "B"].ravel(), minlength=p.n_vertices)
    assert np.all(border_deg[ends] == 2)


# ------------------------------------------------------------------------------------------------ properties

from hypothesis import example, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

coord = st.floats(min_value=-100, max_value=100, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(
    pts=st.lists(st.tuples(coord, coord), min_size=4, max_size=4),
    interval=st.floats(min_value=1.0, max_value=30.0),
    tolerance=st.floats(min_value=0.005, max_value=2.0),
)
# handles on one point: a near-cusp (speed 1 % of the fastest) whose sides were refined at their own midpoints
@example(pts=[(0.0, 1.0), (0.0, 0.0), (0.0, 0.0), (1.0, 5.0)], interval=1.0, tolerance=0.015625)
@example(pts=[(0.0, 0.0), (2.0, 0.0), (9.0, 2.0), (0.0, 0.0)], interval=2.0, tolerance=0.03125)
# a lamp-shade strip's S-shaped crease (a designer session): it passes through its chord's midpoint, 2.3 mm from the
# chord elsewhere, and was kept as one straight chord
@example(pts=[(0.0, 0.0), (8.0, 10.0), (-8.0, 20.0), (0.0, 30.0)], interval=46.67, tolerance=0.47)
def test_any_cubic_meets_interval_and_tolerance(pts, interval, tolerance) -> None:
    """Chords no longer than the interval, and the curve within the tolerance of them at the middle of each chord
    (where it is refined) and, within a quarter more, anywhere along it (16 points per chord)."""
    seg = CurveSegment("cubic", np.array(pts, dtype=float))
    t = curve_parameters(seg, interval, tolerance)
    assert t[0] == 0.0 and t[-1] == 1.0 and np.all(np.diff(t) > 0)
    p = seg.evaluate(t)
    assert np.hypot(*np.diff(p, axis=0).T).max() <= interval * (1 + 1e-9)
    ab = p[1:] - p[:-1]
    ll = np.einsum("ij,ij->i", ab, ab)
    for f, bound in [(0.5, tolerance)] + [(f, 1.25 * tolerance) for f in np.linspace(0.0, 1.0, 17)[1:-1]]:
        q = seg.evaluate(t[:-1] + f * np.diff(t))
        u = np.clip(np.einsum("ij,ij->i", q - p[:-1], ab) / np.where(ll > 0, ll, 1), 0, 1)
        assert np.hypot(*(q - (p[:-1] + u[:, None] * ab)).T).max() <= bound, f


def _cross2(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """z of the cross product of rows of 2-D vectors (numpy 2 deprecates np.cross on 2-D vectors)."""
    return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]


@settings(max_examples=40, deadline=None)
@given(
    lines=st.lists(st.tuples(coord, coord, coord, coord), min_size=2, max_size=25),
)
# both ends of a segment one merge tolerance long lie on the vertical line: split it once, at the exact vertex
@example(lines=[(0.001, 0, 0, 0), (0, 0, 1, 1), (0, 1, 0, -1)])
# a crossing inside one segment a merge tolerance from the other's end, that end as far from the first's
@example(lines=[(0.0, 0.0, 1.0, 1.0), (1.0, 0.0, 0.0, 0.001)])
# a crossing within a merge tolerance of an end of each segment, those ends a merge tolerance apart: snap it to one
@example(lines=[(1.0, 0.0, 0.001, 0.002), (0.0, 0.0, 0.002, 0.002)])
# a free end 0.001 from a junction, drawn on to the stroke its continuation hits: it would pass 1e-4 from the junction
@example(lines=[(-100.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, -100.0), (1.0, 0.0005, 0.001, 0.0001)])
# a free end drawn on to the end of the piece it hits: the piece to that end (not to the hit) crosses a third stroke
@example(lines=[(0.0, 100.0, 0.0, 0.0), (1.0, 0.002, -100.0, 1.0), (0.0, 0.001, 0.5, 0.002), (0.0, -1.0, 0.999, 0.002)])
# thinning: a chord across a stretch of its chain ran within the tolerance of another stretch of it (all of the
# chain's vertices were ignored), and a closed loop could shrink to a chord back to its start
@example(lines=[(0.0, 0.0, 0.0, 1.0), (0.0, 1.0, 1.0, 1.0), (0.0, 0.0, 1.5, 1.0)])
@example(
    lines=[
        (-1.0, 0.0005, 0.15912802612053012, 1.5),
        (2.0, -0.40141500866660484, -100.0, -0.030998331454241246),
        (0.0, 0.0, -100.0, 0.999),
        (0.0, 0.5, 1.0, 0.001),
        (-1.0, 0.0001, 0.0, 0.0005),
    ]
)
def test_random_segments_become_a_planar_graph(lines) -> None:
    """After the clean-up no two segments cross or overlap, and no vertex lies inside another segment."""
    curves = [
        CreaseCurve([line((x0, y0), (x1, y1))], "M" if k % 2 else "V", 90.0, source=f"l{k}")
        for k, (x0, y0, x1, y1) in enumerate(lines)
    ]
    tol = 1e-3
    try:
        p = discretize(curves, interval=1000, tolerance=1, merge_tolerance=tol)
    except PatternError:
        return  # every segment degenerate
    a, b = chords(p)
    r = b - a
    length = np.hypot(*r.T)
    assert length.min() >= tol
    # no vertex strictly inside a segment (farther than tol from both ends, closer than tol/10 to the line)
    v = p.vertices
    rel = v[None, :, :] - a[:, None, :]
    along = np.einsum("evk,ek->ev", rel, r) / length[:, None]
    off = np.abs(r[:, None, 0] * rel[..., 1] - r[:, None, 1] * rel[..., 0]) / length[:, None]
    inside = (along > 2 * tol) & (along < length[:, None] - 2 * tol) & (off < tol / 10)
    assert not inside.any()
    # no proper crossings between segments that share no vertex
    i, j = np.triu_indices(len(a), 1)
    share = (p.edges[i][:, :, None] == p.edges[j][:, None, :]).any(axis=(1, 2))
    d1 = _cross2(r[i], a[j] - a[i])
    d2 = _cross2(r[i], b[j] - a[i])
    d3 = _cross2(r[j], a[i] - a[j])
    d4 = _cross2(r[j], b[i] - a[j])
    margin = 1e-6 * (length[i] * length[j])
    crossing = (d1 * d2 < -(margin**2)) & (d3 * d4 < -(margin**2)) & ~share
    assert not crossing.any()


def test_lines_through_a_junction_that_miss_it_by_a_hair_snap_to_it() -> None:
    hub = (50.0, 50.0)
    spokes = [
        CreaseCurve([line(hub, (50 + 40 * math.cos(a), 50 + 40 * math.sin(a)))], "M", -90.0, source=f"s{k}")
        for k, a in enumerate((0.3, 2.0, 4.0))
    ]
    # two long facet lines meant to pass through the hub, off by 0.01 mm (merge tolerance 0.005 mm)
    f1 = CreaseCurve([line((10, 10.01), (90, 90.01))], "F", 0.0, source="f1")
    f2 = CreaseCurve([line((10, 89.99), (90, 9.99))], "F", 0.0, source="f2")
    p = discretize([*spokes, f1, f2], interval=100, tolerance=1, merge_tolerance=0.005)
    lengths = np.hypot(*np.subtract(*chords(p)).T)
    assert lengths.min() > 30  # no slivers at the hub
    assert p.count("F") == 4 and p.count("M") == 3 and p.n_vertices == 8
    h = int(np.argmin(np.hypot(*(p.vertices - hub).T)))
    np.testing.assert_array_equal(p.vertices[h], hub)  # the drawn junction keeps its place
    assert np.count_nonzero(p.edges == h) == 7


def test_curved_pleat_simple_hub_is_clean() -> None:
    p = discretize(read_svg(FIXTURES / "curvedPleatSimple.svg").curves)
    assert (p.count("M"), p.count("V"), p.count("F")) == (1, 1, 14)
    assert not p.warnings


def test_curve_samples_a_hair_from_a_junction_are_removed_within_tolerance(monkeypatch) -> None:
    """Issue 12: a parabola passes near the corner where two straight creases meet and crosses one of them beside
    one of its own sample points. Removing such samples (within the tolerance) raises the smallest corner any
    triangulation must have from 0.46° to 1.17°; every removed sample stays within the tolerance of the new
    polyline. No fixture or example has such a sample (their mesh digests are unchanged)."""
    from curved_fold.core.io.svg import parse_svg_text
    from curved_fold.core.metrics.mesh_quality import forced_smallest_corner
    from curved_fold.core.pattern import discretize as disc

    svg = (
        '<svg xmlns="http://www.w3.org/2000/svg" width="150mm" height="150mm" viewBox="0 0 150 150">'
        '<rect x="0" y="0" width="150" height="150" fill="none" stroke="#000000"/>'
        '<path d="M 75 0 L 75 75" stroke="#0000ff" opacity="0.5"/>'
        '<path d="M 75 75 L 150 100" stroke="#0000ff" opacity="0.5"/>'
        '<path d="M 0 140 Q 75.0 10.3 150 140" stroke="#ff0000" opacity="0.5"/></svg>'
    )
    curves = parse_svg_text(svg, "t.svg").curves
    fixed = disc.discretize(curves)
    monkeypatch.setattr(disc, "JUNCTION_SLIVER_FRACTION", 0.0)
    plain = disc.discretize(curves)
    assert fixed.n_vertices < plain.n_vertices
    # straight creases whole (an infinite interval): the needle split (core.mesh.needles) would hide the difference
    whole = [replace(p, interval=math.inf) for p in (plain, fixed)]
    assert forced_smallest_corner(whole[0]) < 0.5 < 1.1 < forced_smallest_corner(whole[1])
    _, tolerance, _ = disc.default_parameters(150.0)
    kept = {tuple(v) for v in fixed.vertices.round(9).tolist()}
    gone = np.array([v for v in plain.vertices.round(9).tolist() if tuple(v) not in kept])
    a, b = fixed.vertices[fixed.edges[:, 0]], fixed.vertices[fixed.edges[:, 1]]
    for p in gone:
        d = disc.point_segment_distance(np.repeat(p[None], len(a), axis=0), a, b).min()
        assert d <= tolerance


def test_a_crease_sample_beside_its_crossing_with_a_curved_border_is_removed_too() -> None:
    """A crease crossing a curved (heart-shaped) border: the border's sample beside the crossing was removed, and
    then no other at that junction, so the crease kept a 0.073 mm stub (a designer session's drawing at a 3 mm
    interval, fifteenth pass), and a 0.97° corner. One sample per drawn curve may now go at a junction, each in its
    own sector."""
    from curved_fold.core.mesh.build import build_mesh
    from curved_fold.core.mesh.fold_mesh import corner_angles

    svg = (
        '<svg xmlns="http://www.w3.org/2000/svg" width="150mm" height="150mm" viewBox="0 0 150 150">'
        '<path id="heart" d="M 75 140 C 20 100 0 60 20 30 C 35 5 65 10 75 35 C 85 10 115 5 130 30 C 150 60 130 100 '
        '75 140 Z" fill="none" stroke="#000000"/>'
        '<path id="c0" d="M 57 0 C 45.2 50 67 90 60.6 150" fill="none" stroke="#ff0000" stroke-opacity="0.5"/></svg>'
    )
    pattern = discretize(parse_svg_text(svg, "heart.svg").curves, interval=3.0)
    e = pattern.edges
    length = np.hypot(*(pattern.vertices[e[:, 1]] - pattern.vertices[e[:, 0]]).T)
    assert length.min() > 1.0  # the stub is gone (and the border's pieces are 1.5 mm)
    mesh = build_mesh(pattern)
    assert corner_angles(mesh.vertices, mesh.triangles).min() > 1.0


def test_a_cusp_is_a_vertex_and_said_not_sampled_down_to_the_merge_tolerance() -> None:
    """A cubic whose handles cross stops and turns back: a cusp (a designer session, fifteenth pass). A chord across
    it strays from the curve in proportion to its length, so halving never met the tolerance: the curve was sampled
    down to the merge tolerance there, the warning asked for a larger tolerance (which changed nothing) and 82 mm
    triangles fanned onto the stretch (13 corners under 1°, down to 0.11°). The cusp is now a vertex, each side
    sampled along its length, and a warning says where it is."""
    from curved_fold.core.mesh.build import build_mesh
    from curved_fold.core.mesh.fold_mesh import corner_angles

    seg = CurveSegment("cubic", np.array([[20.0, 0.0], [140.0, -120.0], [20.0, -120.0], [140.0, 0.0]]))
    t = curve_parameters(seg, 10.0, 0.075)
    assert np.any(np.abs(t - 0.5) < 1e-9)  # the cusp, at t = 1/2 (B′(½) = 0)
    chords = np.hypot(*np.diff(seg.evaluate(t), axis=0).T)
    assert chords.min() > 1.0 and chords.max() <= 10.0
    svg = (
        '<svg xmlns="http://www.w3.org/2000/svg" width="160mm" height="160mm" viewBox="0 0 160 160">'
        '<rect x="0" y="0" width="160" height="160" fill="none" stroke="#000000"/>'
        '<path id="cusp" d="M 20 0 C 140 120 20 120 140 0" fill="none" stroke="#0000ff" stroke-opacity="0.5"/></svg>'
    )
    pattern = discretize(parse_svg_text(svg, "cusp.svg").curves)
    assert not any("merge tolerance" in w for w in pattern.warnings)
    assert any(
        "<path id='cusp'> (line 1) has a cusp at (80.0, -90.0) mm: the curve (nearly) stops" in w
        for w in pattern.warnings
    )
    mesh = build_mesh(pattern)
    assert corner_angles(mesh.vertices, mesh.triangles).min() > 1.0


def test_a_near_cusp_is_a_cusp_too() -> None:
    """Handles 2 mm short of crossing on a 150 mm sheet (a review session): the curve nearly stops and turns back
    (its slowest point 0.3 % of its fastest). With cusps at 0.1 %, it kept the old sampling down to the merge
    tolerance and 4 corners under 1° (0.20°); at 2 % it is a cusp, and none is left."""
    from curved_fold.core.mesh.build import build_mesh
    from curved_fold.core.mesh.fold_mesh import corner_angles

    svg = (
        '<svg xmlns="http://www.w3.org/2000/svg" width="150mm" height="150mm" viewBox="0 0 150 150">'
        '<rect x="0" y="0" width="150" height="150" fill="none" stroke="#000000"/>'
        '<path id="nc" d="M 0 75 C 140 130 -8 130 150 75" fill="none" stroke="#0000ff" stroke-opacity="0.5"/></svg>'
    )
    pattern = discretize(parse_svg_text(svg, "nc.svg").curves)
    assert any("<path id='nc'> (line 1) has a cusp at" in w for w in pattern.warnings)
    mesh = build_mesh(pattern)
    assert corner_angles(mesh.vertices, mesh.triangles).min() > 1.0


# ------------------------------------------------------------------------------------------------ flattened curves


def _arc_points(n: int) -> np.ndarray:
    """``n + 1`` points of an arc of radius 100 mm about (−40, 50), from the bottom to the top side of the 100 mm
    square: a crease across the sheet, turning 3.75° per piece for ``n`` = 16."""
    t = np.linspace(-math.pi / 6, math.pi / 6, n + 1)
    return np.column_stack([-40.0 + 100.0 * np.cos(t), 50.0 + 100.0 * np.sin(t)])


def _svg_lines(points: np.ndarray, stroke: str, opacity: float = 0.5) -> str:
    """One Origami Simulator ``<line>`` per piece (coordinates as ``repr``, y up → SVG's y down)."""
    return "\n".join(
        f'<line stroke="{stroke}" opacity="{opacity}" x1="{a[0]!r}" y1="{100 - a[1]!r}" '
        f'x2="{b[0]!r}" y2="{100 - b[1]!r}"/>'
        for a, b in zip(points[:-1].tolist(), points[1:].tolist(), strict=True)
    )


def _points_attr(points: np.ndarray) -> str:
    return " ".join(f"{x!r},{100 - y!r}" for x, y in points.tolist())


def test_curves_drawn_as_polylines_or_lines_are_curve_pieces() -> None:
    """Paper §3.3 scores only curve pieces: a curve drawn as a polyline (a tool that flattens Béziers) or as
    separate ``<line>`` elements (Origami Simulator's files) is one; a straight crease cut into pieces, a zigzag
    with corners and a stroke with a Bézier in it (whose straight pieces say they are straight) are not."""
    arc = _arc_points(16)
    straight = np.array([(10.0, 20.0), (30.0, 20.0), (50.0, 20.0), (70.0, 20.0)])
    zigzag = np.array([(10.0, 70.0), (20.0, 80.0), (30.0, 70.0), (40.0, 80.0)])  # 90° turns
    body = (
        '<rect stroke="#000000" fill="none" x="0" y="0" width="100" height="100"/>\n'
        f'<polyline stroke="#ff0000" opacity="0.5" fill="none" points="{_points_attr(arc)}"/>\n'
        f'<polyline stroke="#0000ff" opacity="0.5" fill="none" points="{_points_attr(straight)}"/>\n'
        f'<polyline stroke="#0000ff" opacity="0.5" fill="none" points="{_points_attr(zigzag)}"/>\n'
        '<path stroke="#ff0000" opacity="0.25" fill="none" d="M 80 100 L 85 90 C 90 80 90 70 85 60 L 100 50"/>\n'
    )
    head = '<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100">\n'
    p = discretize(parse_svg_text(head + body + "</svg>").curves)
    v = p.vertices - p.vertices.min(axis=0)  # the sheet's corner at the origin, as drawn (SVG's y down → y up)
    a, b = v[p.edges[:, 0]], v[p.edges[:, 1]]
    mid = 0.5 * (a + b)
    on_arc = (p.assignments == "M") & (np.abs(np.hypot(mid[:, 0] + 40, mid[:, 1] - 50) - 100) < 1.0)
    assert on_arc.sum() == 17 and p.edge_from_curve[on_arc].all()  # 16 pieces, one split where the V crosses
    assert not p.edge_from_curve[p.assignments == "V"].any()  # the straight crease and the zigzag
    assert not p.edge_from_curve[p.assignments == "B"].any()
    path_lines = (p.assignments == "M") & ~on_arc & (np.hypot(*(b - a).T) > 4)  # the path's two L pieces
    assert path_lines.sum() == 2 and not p.edge_from_curve[path_lines].any()
    # the same arc as separate <line> elements, as Origami Simulator writes it
    lines = discretize(
        parse_svg_text(head + body.splitlines()[0] + "\n" + _svg_lines(arc, "#ff0000") + "</svg>").curves
    )
    assert lines.count("M") == 16 and lines.edge_from_curve[lines.assignments == "M"].all()


def test_flattened_curves_need_one_role_and_angle_and_no_facet_lines() -> None:
    """A chain runs only through vertices where two segments of one assignment and angle meet: an arc whose
    vertices carry facet lines, or whose two halves fold to different angles, is judged piece by chain; a closed
    polygon of a curve is a curve, a square (90° corners) is not."""
    arc = _arc_points(16)
    n = len(arc)
    edges = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    role = np.array(["M"] * (n - 1))
    angle = np.full(n - 1, -90.0)
    assert flattened_curves(arc, edges, role, angle, 0.07).all()
    assert not flattened_curves(arc, edges, role, angle, 100.0).any()  # within the tolerance of one chord
    # a facet line at every inner vertex: no vertex where exactly two meet
    hub = np.vstack([arc, [[80.0, 50.0]]])
    facets = np.column_stack([np.arange(1, n - 1), np.full(n - 2, n)])
    both = np.vstack([edges, facets])
    flags = flattened_curves(hub, both, np.r_[role, ["F"] * (n - 2)], np.r_[angle, np.zeros(n - 2)], 0.07)
    assert not flags.any()
    # two halves at different angles: two chains, each still a curve
    angle2 = np.where(np.arange(n - 1) < 8, -90.0, -60.0)
    assert flattened_curves(arc, edges, role, angle2, 0.07).all()
    # two halves of one straight line at different angles, meeting at the midpoint: straight
    line_pts = np.column_stack([np.linspace(0, 100, 9), np.full(9, 50.0)])
    line_edges = np.column_stack([np.arange(8), np.arange(1, 9)])
    assert not flattened_curves(line_pts, line_edges, np.array(["V"] * 8), np.full(8, 90.0), 0.07).any()
    # closed: a 24-gon is a curve; a square is not
    t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    ring = np.column_stack([50 + 30 * np.cos(t), 50 + 30 * np.sin(t)])
    loop = np.column_stack([np.arange(24), (np.arange(24) + 1) % 24])
    assert flattened_curves(ring, loop, np.array(["V"] * 24), np.full(24, 45.0), 0.07).all()
    sq = np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)])
    sq_edges = np.array([(0, 1), (1, 2), (2, 3), (3, 0)])
    assert not flattened_curves(sq, sq_edges, np.array(["B"] * 4), np.full(4, np.nan), 0.07).any()


def test_an_outline_drawn_as_one_open_stroke_back_to_its_start_is_read_at_once() -> None:
    """Its two loose ends coincide: the near-pair grid made each of them 2,048² cells (a second of one Blender job
    slice, a 4-million-entry array) before its cell was at least twice the merge tolerance."""
    outline = [(0.0, 0.0), (1000.0, 0.0), (1000.0, 600.0), (0.0, 600.0), (0.0, 0.0)]
    border = CreaseCurve([line(outline[k], outline[k + 1]) for k in range(4)], "B", None, source="outline")
    crease = CreaseCurve([line((500.0, 0.0), (500.0, 600.0))], "V", 90.0, source="crease")
    steps = discretize_steps([border, crease])
    t0 = time.perf_counter()
    assert next(steps) == "parameters"
    assert time.perf_counter() - t0 < 0.25
    p = discretize([border, crease])
    assert p.count("V") == 1 and not p.warnings


def test_a_flattened_curve_border_is_still_split_at_the_interval_and_a_12_gon_is_a_curve() -> None:
    """A border read as a flattened curve keeps the border's split at the interval (the rulings need border
    vertices to end at): a circle drawn as a 24-gon of 26 mm chords had them whole once it was read as a curve.
    A circle of 12 pieces turns exactly 30° at each vertex, and the digits it is written with decided which
    vertices counted (8 of 12 pieces); now all do."""
    t = np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)
    ring = np.column_stack([100.0 + 100.0 * np.cos(t), 100.0 + 100.0 * np.sin(t)])
    t12 = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False) + 0.1
    circle = np.column_stack([100.0 + 40.0 * np.cos(t12), 100.0 + 40.0 * np.sin(t12)])
    head = '<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="200mm" viewBox="0 0 200 200">\n'
    body = (
        f'<polygon stroke="#000000" fill="none" points="{_points_attr(ring)}"/>\n'
        f'<polygon stroke="#0000ff" opacity="0.5" fill="none" points="'
        + " ".join(f"{x:.6f},{100 - y:.6f}" for x, y in circle.tolist())
        + '"/>\n'
    )
    p = discretize(parse_svg_text(head + body + "</svg>").curves)
    interval = default_parameters(200.0)[0]
    a, b = p.vertices[p.edges[:, 0]], p.vertices[p.edges[:, 1]]
    border = p.assignments == "B"
    assert np.hypot(*(b - a)[border].T).max() <= interval * (1 + 1e-9)
    assert border.sum() == 24 * math.ceil(2 * 100 * math.sin(math.pi / 24) / interval)
    assert p.edge_from_curve[border].all()
    assert p.count("V") == 12 and p.edge_from_curve[p.assignments == "V"].all()


def test_inside_border_in_bands_counts_as_every_point_against_every_segment() -> None:
    """``_inside_border`` takes the points in horizontal bands against the border segments that meet each band (0.5 s
    → a few ms for 27,800 pieces inside a border of 3,224): the same answer as the plain even-odd count, on random
    star polygons, with points on their vertices and on rounded coordinates."""
    from curved_fold.core.pattern.discretize import _inside_border

    def every_pair(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        ay, by, ax, bx = a[:, 1], b[:, 1], a[:, 0], b[:, 0]
        px, py = points[:, 0:1], points[:, 1:2]
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = ax + (py - ay) * (bx - ax) / (by - ay)
        return (np.count_nonzero(((ay > py) != (by > py)) & (px < xc), axis=1) % 2) == 1

    rng = np.random.default_rng(20261126)
    for trial in range(40):
        n = int(rng.integers(3, 400))
        t = np.sort(rng.uniform(0.0, 2.0 * np.pi, n))
        r = rng.uniform(0.5, 1.5, n)
        poly = np.column_stack([r * np.cos(t), r * np.sin(t)])
        if trial % 4 == 0:
            poly = np.round(poly, 1)
        pts = rng.uniform(-2.0, 2.0, (int(rng.integers(1, 3000)), 2))
        pts[: min(50, len(pts))] = poly[rng.integers(0, n, min(50, len(pts)))]
        a, b = poly, np.roll(poly, -1, axis=0)
        np.testing.assert_array_equal(_inside_border(pts, a, b), every_pair(pts, a, b), err_msg=str(trial))


def test_an_end_moved_onto_the_border_does_not_double_it() -> None:
    """The fuzz run (seed 3, 2,000 patterns, nine of them) found a crease that enters the sheet across its edge and
    ends 0.68 mm inside it, running at 8° to that edge: its free end is moved onto the border (the nearest point), so
    its last piece lay along the border piece between the crossing and that point, two segments on the same two
    vertices, and the triangulation refused the pattern ("pattern edges 88 and 89 join the same two vertices"). The
    piece is the border's: it is kept once, as border, with the duplicates' warning, and the sheet folds."""
    from curved_fold.core.pipeline import fold_pattern

    border = CreaseCurve(
        [line((0, 0), (150, 0)), line((150, 0), (150, 150)), line((150, 150), (0, 150)), line((0, 150), (0, 0))],
        "B",
        None,
        closed=True,
        source="border",
    )
    valley = CreaseCurve([line((10, 40), (140, 40))], "V", 90.0, source="valley")
    slant = CreaseCurve([line((-15.0, -15.0), (0.679966694023669, 96.39640602312231))], "M", -90.0, source="slant")
    pattern = discretize([border, valley, slant])
    key = np.sort(pattern.edges, axis=1)
    assert len(np.unique(key, axis=0)) == len(key)
    assert any("stopped short of the border" in w for w in pattern.warnings)
    assert any("kept border (B) over slant (M)" in w for w in pattern.warnings), pattern.warnings
    report = fold_pattern(pattern, percent=1.0).report
    assert report["converged"], report["message"]


def test_a_polyline_twice_as_dense_as_the_paper_samples_is_thinned() -> None:
    """A designer session's sine valley drawn as a 300-point polyline (1.34 mm pieces) on a 400 mm sheet
    (``tests/data/dense_sine_polyline_400.svg``): at a 5 mm interval it was kept point for point (thinned only under
    a quarter of the interval), and the border's vertices fanned 482 corners under 1° onto it; at 8 mm it was
    thinned and had none. Under half the interval it is thinned now."""
    from curved_fold.core.mesh.build import build_mesh
    from curved_fold.core.mesh.fold_mesh import corner_angles

    path = Path(__file__).resolve().parent / "data" / "dense_sine_polyline_400.svg"
    pattern = discretize(read_svg(path).curves, interval=5.0)
    assert np.count_nonzero(pattern.assignments == "V") < 200
    mesh = build_mesh(pattern)
    assert corner_angles(mesh.vertices, mesh.triangles).min() > 1.0


def test_a_polyline_drawn_finer_than_the_tolerance_is_thinned() -> None:
    """A designer session's three sine creases drawn as 3,001-point polylines, 0.05 mm apart, on a 150 mm sheet:
    the next point of a chain always lies within the tolerance (0.07 mm) of a chord's end, so every chord was found
    not clear of its own chain and nothing was thinned: 17,976 faces, 17,892 corners under 1°, 40 s; at 0.1 mm
    spacing the same curves gave 282 faces. The points a chain goes on through within the tolerance of a chord's
    ends are no obstacle now."""
    from curved_fold.core.mesh.build import build_mesh
    from curved_fold.core.mesh.fold_mesh import corner_angles

    u = np.linspace(0.0, 1.0, 3001)
    lines = "".join(
        f'<polyline fill="none" stroke="{colour}" opacity="0.5" points="'
        + " ".join(f"{x0 + 8.0 * math.sin(2 * math.pi * float(t))!r},{100.0 * float(t)!r}" for t in u)
        + '"/>'
        for x0, colour in ((40.0, "#0000ff"), (75.0, "#ff0000"), (110.0, "#0000ff"))
    )
    svg = (
        '<svg xmlns="http://www.w3.org/2000/svg" width="150mm" height="100mm" viewBox="0 0 150 100">'
        '<rect x="0" y="0" width="150" height="100" fill="none" stroke="#000000"/>' + lines + "</svg>"
    )
    t0 = time.process_time()
    pattern = discretize(parse_svg_text(svg, "fine.svg").curves)
    mesh = build_mesh(pattern)
    assert mesh.n_faces < 400 and corner_angles(mesh.vertices, mesh.triangles).min() > 1.0
    assert time.process_time() - t0 < 5.0  # it took 40 s with the fold


def test_thinning_tests_a_few_chords_per_chord_kept(monkeypatch) -> None:
    """A chord that passes too near another vertex is shortened by bisection, not one point at a time: a CLI review
    session's 150,000-point circle (a FOLD file within every limit) made 90,000 tests of nearby vertices and took
    40 s. Here a dense circle with a second one a tolerance away inside it, so that long chords are not clear."""
    from curved_fold.core.pattern import polylines

    calls = []
    real = polylines.point_segment_distance
    monkeypatch.setattr(polylines, "point_segment_distance", lambda *a: calls.append(1) or real(*a))
    n = 20_000
    th = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    outer = np.c_[100 * np.cos(th), 100 * np.sin(th)]
    inner = np.c_[99.93 * np.cos(th[::50]), 99.93 * np.sin(th[::50])]  # 0.07 mm inside: obstacles to long chords
    v = np.r_[outer, inner]
    e = np.c_[np.arange(n), (np.arange(n) + 1) % n]
    kept, chords, _ = polylines.thin_dense_polylines(
        v, e, np.array(["B"] * n), np.full(n, np.nan), np.ones(n, bool), 5.0, 0.1
    )
    assert len(chords) > 100
    steps = len(chords) + int(kept.sum())  # a chord, or a piece kept as drawn
    assert len(calls) <= 14 * steps, (len(calls), steps)


def test_thinning_a_tight_spiral_takes_bounded_memory() -> None:
    """A review session's 20,000-point spiral of 0.15 mm pitch: thousands of its points lie within the interval of
    each start, and the candidate chords' arrays (count × count) took 12 GB before the process was killed (6,000
    points: 12 s, 560 MB). A chord is looked for only as far along the polyline as twice the interval."""
    import tracemalloc

    from curved_fold.core.pattern.polylines import thin_dense_polylines

    n = 8_000  # 20,000 before the process was killed; 8,000 needed ~1 GB
    th = np.linspace(0.0, n / 100 * np.pi, n)
    r = 1.0 + 0.15 * th / (2 * np.pi)
    v = np.c_[r * np.cos(th), r * np.sin(th)]
    e = np.c_[np.arange(n - 1), np.arange(1, n)]
    tracemalloc.start()
    t0 = time.process_time()
    kept, chords, _ = thin_dense_polylines(
        v, e, np.array(["V"] * (n - 1)), np.full(n - 1, 90.0), np.ones(n - 1, bool), 5.0, 0.1
    )
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 150e6 and time.process_time() - t0 < 30.0
    assert 0 < int(kept.sum()) + len(chords) < n // 2  # thinned
