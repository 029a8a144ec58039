"""Ruling-aware edge swaps (core.mesh.ruling, paper §3.3) on the exact bisector case, hand-made cases and fixtures."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np
import pytest

from curved_fold.core.io.reader import read_pattern
from curved_fold.core.mesh.build import build_mesh
from curved_fold.core.mesh.ruling import EndpointScorer, ruling_swaps
from curved_fold.core.mesh.triangulate import constrained_triangulation
from tests.analytic import bisector_case

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "origami-simulator"
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SVGS = sorted(FIXTURES.glob("*.svg"))


def _edge_set(tris: np.ndarray) -> set[tuple[int, int]]:
    s = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    return set(map(tuple, s.tolist()))


def _flip(tris: np.ndarray, a: int, b: int) -> np.ndarray | None:
    """Flip edge ab if its quad is strictly convex (test helper, independent of core.mesh.ruling)."""
    t1 = [i for i, t in enumerate(tris.tolist()) if a in t and b in t]
    if len(t1) != 2:
        return None
    c = [v for v in tris[t1[0]] if v not in (a, b)][0]
    d = [v for v in tris[t1[1]] if v not in (a, b)][0]
    return tris, t1, c, d


def test_endpoint_score_is_zero_on_bisectors() -> None:
    case = bisector_case(n_segments=10)
    pat = case.pattern
    scorer = EndpointScorer(pat.vertices, pat.edges, pat.edge_from_curve)
    for i, j in sorted(case.bisector_edges):
        assert scorer.cost(i, j) == pytest.approx(0.0, abs=1e-20)  # crease end scores 0, doubled
        assert scorer.endpoint(j, i) is None  # border end does not score
    n = case.n_segments
    # a diagonal c_i – L_{i+1} scores > 0; an edge between two border vertices is ∞; crease ends do not score
    assert scorer.cost(3, n + 1 + 4) > 1e-4
    assert math.isinf(scorer.cost(n + 1 + 2, 2 * n + 2 + 3))
    assert scorer.endpoint(0, n + 2) is None


@pytest.mark.parametrize("n_segments", [12, 24, 40])
def test_swaps_recover_exactly_the_bisectors(n_segments: int) -> None:
    case = bisector_case(n_segments=n_segments, width_left=30.0, width_right=45.0)
    mesh = build_mesh(case.pattern, "ruling")
    facets = set(map(tuple, mesh.edges[mesh.assignments == "F"].tolist()))
    assert case.bisector_edges <= facets
    # the other facets are one diagonal per quad: no fan, no second rung
    assert len(facets) == len(case.bisector_edges) + 2 * n_segments
    assert np.all(mesh.signed_areas() > 0)


def test_swaps_restore_bisectors_removed_from_the_mesh() -> None:
    """Start from the ideal mesh with every other bisector flipped away: the swaps must put them back."""
    case = bisector_case(n_segments=24)
    pt = constrained_triangulation(case.pattern)
    tris = case.ideal_triangles()
    removed = 0
    for i, j in sorted(case.bisector_edges)[::2]:
        rows = [k for k, t in enumerate(tris.tolist()) if i in t and j in t]
        c = [v for v in tris[rows[0]] if v not in (i, j)][0]
        d = [v for v in tris[rows[1]] if v not in (i, j)][0]
        new = tris.copy()
        new[rows[0]] = [c, i, d]
        new[rows[1]] = [d, j, c]
        v = case.pattern.vertices[new[rows]]
        area = (v[:, 1, 0] - v[:, 0, 0]) * (v[:, 2, 1] - v[:, 0, 1]) - (v[:, 1, 1] - v[:, 0, 1]) * (
            v[:, 2, 0] - v[:, 0, 0]
        )
        if np.all(area < 0):
            new[rows] = new[rows][:, [0, 2, 1]]
            area = -area
        if np.all(area > 0):
            tris, removed = new, removed + 1
    assert removed >= 8
    assert len(case.bisector_edges & _edge_set(tris)) == len(case.bisector_edges) - removed
    face = np.zeros(len(tris), dtype=np.int64)
    v = case.pattern.vertices
    face[np.mean(v[tris][:, :, 1], axis=1) < v[tris][:, :, 0].mean(axis=1) ** 2 / 120.0] = 1
    seg = case.pattern.edges
    res = ruling_swaps(pt.vertices, tris, face, seg, case.pattern.edge_from_curve)
    assert res.swaps >= removed
    assert case.bisector_edges <= _edge_set(res.triangles)
    a, b, c = (v[res.triangles[:, k]] for k in range(3))
    assert np.all((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) > 0)


def _facet_valence(mesh) -> dict[tuple[int, int], int]:
    from curved_fold.core.metrics.measures import edge_triangles

    f1, _, _, _ = edge_triangles(mesh)
    val: dict[tuple[int, int], int] = {}
    for (a, b), pl, t in zip(mesh.edges.tolist(), mesh.edge_polyline, f1, strict=True):
        if pl < 0:
            f = int(mesh.triangle_face[t])
            val[(a, f)] = val.get((a, f), 0) + 1
            val[(b, f)] = val.get((b, f), 0) + 1
    return val


@pytest.mark.parametrize("path", SVGS, ids=[p.name for p in SVGS])
def test_fixture_swaps_terminate_valid_and_respect_valence(path: Path) -> None:
    reader = pytest.importorskip("curved_fold.core.io.reader", reason="core.io.reader (INPUT helper) not available")
    pat = reader.read_pattern(path)
    cdt = build_mesh(pat, "cdt")
    mesh = build_mesh(pat, "ruling")
    assert np.all(mesh.signed_areas() > 0), "a swap inverted or flattened a triangle"
    assert np.array_equal(np.sort(mesh.triangle_face), np.sort(cdt.triangle_face)), "faces keep their triangles"
    before, after = _facet_valence(cdt), _facet_valence(mesh)
    for key, count in after.items():
        # a vertex only gains facet edges while it has at most 3 in the face, so it ends at ≤ 4 or at its CDT count
        assert count <= max(4, before.get(key, 0)), f"vertex {key[0]} in face {key[1]} has {count} facet edges"
    if pat.edge_from_curve.any() and mesh.swaps:
        assert mesh.swaps > 0


@pytest.mark.slow
def test_swaps_on_a_very_finely_discretised_curve_finish_quickly_without_slivers() -> None:
    """Tolerance 1e-5 mm on a 100 mm sheet: ~5,000 faces with 0.04 mm chords. Before the sliver rule the swaps ran
    ~57,000 times in long dependent chains (over two minutes when applied one whole-mesh ``rotate_edges`` call at a
    time, 6 s batched) and took the smallest corner from the CDT's 0.047° to 0.029°; now every such swap is refused
    (it would sharpen a corner already under 2°), the mesh keeps the CDT's corners and takes well under seconds."""
    import time

    from curved_fold.core.pattern.discretize import discretize
    from curved_fold.core.pattern.model import CreaseCurve, CurveSegment

    c = [(0, 0), (100, 0), (100, 100), (0, 100)]
    square = CreaseCurve(
        [CurveSegment("line", np.array([c[i], c[(i + 1) % 4]], float)) for i in range(4)], "B", None, closed=True
    )
    wave = CreaseCurve([CurveSegment("cubic", np.array([[0, 50], [30, 0], [70, 100], [100, 50]], float))], "V", 90.0)
    pattern = discretize([square, wave], tolerance=1e-5, interval=7.0)
    t0 = time.perf_counter()
    mesh = build_mesh(pattern, "ruling")
    elapsed = time.perf_counter() - t0
    from curved_fold.core.metrics.mesh_quality import corner_summary

    assert mesh.n_faces > 5000 and mesh.swaps < 100
    assert np.all(mesh.signed_areas() > 0)
    ruling, cdt = corner_summary(mesh), corner_summary(build_mesh(pattern, "cdt"))
    assert ruling["smallest_corner_deg"] == pytest.approx(cdt["smallest_corner_deg"])
    assert ruling["corners_below_1deg"] <= cdt["corners_below_1deg"]
    assert elapsed < 30.0, f"{mesh.swaps} swaps on {mesh.n_faces} faces took {elapsed:.1f} s"


def _thin_quad(half_width: float):
    """A curve vertex P (two curve segments along x) under a rhombus P, C, D, A of the given half width: the diagonal
    A–C scores ∞, the swap to P–D (the exact bisector at P) scores 0, so the ruling criterion always wants it."""
    pts = np.array([[-1.0, 0.0], [0.0, 0.0], [1.0, 0.0], [half_width, 5.0], [0.0, 10.0], [-half_width, 5.0]])
    p0, p, p2, c, d, a = range(6)
    tris = np.array([[p, c, a], [a, c, d], [p0, p, a], [p, p2, c]])
    segs = np.array([[p0, p], [p, p2]])
    return pts, tris, segs, (p, d)


def test_swap_refused_when_it_makes_a_sliver() -> None:
    """Half width 0.1 mm: the old triangles' smallest corner is 2.29°, the new ones' 1.15°, below both that and
    SWAP_MIN_CORNER_DEG (2°): refused, counted. Half width 1 mm: new corners ≥ 11°: swapped."""
    from curved_fold.core.mesh.ruling import SWAP_MIN_CORNER_DEG
    from curved_fold.core.metrics.mesh_quality import corner_angles

    pts, tris, segs, (p, d) = _thin_quad(0.1)
    res = ruling_swaps(pts, tris, np.zeros(len(tris), np.int64), segs, np.ones(len(segs), bool))
    assert res.swaps == 0 and res.rejected_sliver == 1
    assert corner_angles(pts, res.triangles).min() == pytest.approx(2 * math.degrees(math.atan(0.1 / 5)))
    pts, tris, segs, (p, d) = _thin_quad(1.0)
    res = ruling_swaps(pts, tris, np.zeros(len(tris), np.int64), segs, np.ones(len(segs), bool))
    assert res.swaps == 1 and res.rejected_sliver == 0
    assert (p, d) in _edge_set(res.triangles)
    assert corner_angles(pts, res.triangles).min() >= SWAP_MIN_CORNER_DEG


@pytest.mark.parametrize("path", SVGS + sorted((FIXTURES.parents[2] / "examples").glob("*.svg")), ids=lambda p: p.name)
def test_ruling_mesh_has_no_sliver_beyond_what_the_pattern_forces(path: Path) -> None:
    """Issue 12: the swaps never take the smallest corner below min(CDT's smallest corner, SWAP_MIN_CORNER_DEG), the
    CDT's being the largest smallest corner any triangulation of the segments can have; and they add no corner under
    1°."""
    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.mesh.ruling import SWAP_MIN_CORNER_DEG
    from curved_fold.core.metrics.mesh_quality import corner_summary, forced_smallest_corner, smallest_segment_gap

    pat = read_pattern(path)
    forced = forced_smallest_corner(pat)
    assert forced <= smallest_segment_gap(pat) + 1e-9
    ruling = corner_summary(build_mesh(pat, "ruling"), forced)
    cdt = corner_summary(build_mesh(pat, "cdt"))
    assert cdt["smallest_corner_deg"] == pytest.approx(forced)
    assert ruling["smallest_corner_deg"] >= min(forced, SWAP_MIN_CORNER_DEG) - 1e-9
    assert ruling["corners_below_1deg"] <= cdt["corners_below_1deg"]


def _as_lines_svg(pattern) -> str:
    """``pattern``'s segments as separate Origami Simulator ``<line>`` elements (opacity = |fold angle| / 180),
    coordinates written exactly: what Origami Simulator, or a tool that flattens curves, gives us."""
    stroke = {"B": "#000000", "M": "#ff0000", "V": "#0000ff", "F": "#ffff00"}
    v = pattern.vertices - pattern.vertices.min(axis=0)
    h = float(v[:, 1].max())
    rows = []
    table = zip(pattern.edges.tolist(), pattern.assignments.tolist(), pattern.fold_angles.tolist(), strict=True)
    for (i, j), a, angle in table:
        (x1, y1), (x2, y2) = v[i].tolist(), v[j].tolist()
        opacity = f' opacity="{abs(angle) / 180.0!r}"' if a in "MV" and math.isfinite(angle) else ""
        rows.append(f'<line stroke="{stroke[a]}"{opacity} x1="{x1!r}" y1="{h - y1!r}" x2="{x2!r}" y2="{h - y2!r}"/>')
    w = float(v[:, 0].max())
    head = f'<svg xmlns="http://www.w3.org/2000/svg" width="{w!r}mm" height="{h!r}mm" viewBox="0 0 {w!r} {h!r}">'
    return "\n".join([head, *rows, "</svg>"])


def _triangles_by_position(mesh) -> set[tuple]:
    v = np.round(mesh.vertices[:, :2] - mesh.vertices[:, :2].min(axis=0), 6)
    return {tuple(sorted(map(tuple, v[t].tolist()))) for t in mesh.triangles}


@pytest.mark.parametrize("path", [EXAMPLES / "single_curve.svg", FIXTURES / "Rotating_Star.svg"], ids=lambda p: p.stem)
def test_a_curve_drawn_as_lines_gets_the_ruling_mesh_of_the_bezier(path: Path, tmp_path: Path) -> None:
    """Paper §3.3 on a curve that comes as straight pieces (separate SVG lines, a plain FOLD file): the swaps align
    the facets with its rulings as they do for the Bézier it was sampled from — the very same mesh. They scored
    only Bézier pieces before, and such files got the plain constrained Delaunay mesh."""
    bezier = read_pattern(path)
    assert bezier.edge_from_curve.any()
    want = _triangles_by_position(build_mesh(bezier))
    svg = tmp_path / "lines.svg"
    svg.write_text(_as_lines_svg(bezier))
    lines = read_pattern(svg)
    assert lines.edge_from_curve.sum() == bezier.edge_from_curve.sum()
    assert _triangles_by_position(build_mesh(lines)) == want
    v = bezier.vertices - bezier.vertices.min(axis=0)
    fold = tmp_path / "plain.fold"
    angles = np.nan_to_num(bezier.fold_angles, nan=0.0)
    fold.write_text(
        json.dumps(
            {
                "file_spec": 1.1,
                "vertices_coords": v.tolist(),
                "edges_vertices": bezier.edges.tolist(),
                "edges_assignment": bezier.assignments.tolist(),
                "edges_foldAngle": angles.tolist(),
            }
        )
    )
    plain = read_pattern(fold)
    assert plain.edge_from_curve.sum() == bezier.edge_from_curve.sum()
    assert _triangles_by_position(build_mesh(plain)) == want


def test_mesh_in_units_is_the_same_mesh_and_the_swaps_are_sliced() -> None:
    """A Blender job runs ``build_mesh_steps`` one unit per slice. Carved_Cylinder at a 1 mm interval (4,476 faces,
    1,251 swaps) gets the same mesh as ``build_mesh``, in units none of which holds the whole swap loop: as one
    unit, the swaps of such a pattern froze Blender for 0.5–0.7 s."""
    from curved_fold.core.mesh.build import build_mesh_steps
    from curved_fold.core.mesh.ruling import SWAP_UNIT_POPS

    pattern = read_pattern(FIXTURES / "Carved_Cylinder.svg", interval=1.0)
    whole = build_mesh(pattern)
    runs = []  # three runs: each unit's time taken as its fastest, so a pause of the shared machine is no unit's
    for _ in range(3):
        steps = build_mesh_steps(pattern)
        names, times = [], []
        while True:
            t0 = time.perf_counter()
            try:
                names.append(next(steps))
            except StopIteration as done:
                mesh = done.value
                times.append(time.perf_counter() - t0)
                break
            times.append(time.perf_counter() - t0)
        for key in ("vertices", "triangles", "edges", "assignments", "edge_from_curve", "triangle_face"):
            np.testing.assert_array_equal(getattr(mesh, key), getattr(whole, key), err_msg=key)
        assert 0 < mesh.generation_ms <= 1e3 * sum(times) * 1.05
        runs.append((names, times))
    assert all(r[0] == names for r in runs)  # the same units each time
    times = np.min([r[1] for r in runs], axis=0)
    assert mesh.swaps == whole.swaps > 1000
    assert names[0] == "triangulated" and names[1] == "swap candidates scored"
    assert names.count("ruling swaps") >= mesh.swaps // SWAP_UNIT_POPS  # at least one pop per swap
    assert "bmesh built" in names and names.count("swaps applied") >= 2 and names[-1] == "cuts split"
    assert max(times) < 0.3 * sum(times)


def _dense_arc_svg(step: float, decimals: int | None, crossed: bool = True) -> str:
    """A 150 mm sheet with a valley arc drawn as a polyline of ``step`` mm pieces, its coordinates rounded to
    ``decimals`` (None: exact), and (``crossed``) a straight mountain crossing it."""
    n = int(round(100.0 * math.pi / 3.0 / step))
    t = np.linspace(-math.pi / 6.0, math.pi / 6.0, n + 1)
    pts = np.column_stack([-40.0 + 100.0 * np.cos(t) + 40.0, 75.0 + 100.0 * np.sin(t) * 1.5])
    fmt = (lambda x: f"{x:.{decimals}f}") if decimals is not None else repr
    points = " ".join(f"{fmt(x)},{fmt(150.0 - y)}" for x, y in pts.tolist())
    return (
        '<svg xmlns="http://www.w3.org/2000/svg" width="150mm" height="150mm" viewBox="0 0 150 150">\n'
        '<rect stroke="#000000" fill="none" x="0" y="0" width="150" height="150"/>\n'
        f'<polyline stroke="#0000ff" opacity="0.5" fill="none" points="{points}"/>\n'
        + ('<line stroke="#ff0000" opacity="0.5" x1="0" y1="75" x2="150" y2="75"/>\n' if crossed else "")
        + "</svg>\n"
    )


def test_a_polyline_far_finer_than_the_interval_is_thinned_and_folds_clean(tmp_path: Path) -> None:
    """A curve drawn as a polyline far finer than the interval is thinned to the paper's sampling: drawn vertices
    only, every dropped one within the tolerance of its chord, chords within the interval, the crossing kept. Kept
    vertex for vertex, 0.05 mm pieces rounded to two decimals folded as a zigzag (fold-angle error 75°), and a 1 m
    sheet of 1 mm polylines made 52,326 faces (245 s) where its Béziers make 2,348."""
    from curved_fold.core.pattern.discretize import default_parameters
    from curved_fold.core.pipeline import fold_pattern

    interval, tolerance, _ = default_parameters(150.0)
    svg = tmp_path / "dense.svg"
    svg.write_text(_dense_arc_svg(0.05, 2))
    p = read_pattern(svg)
    drawn = read_pattern(svg, interval=0.01)  # an interval finer than the pieces keeps every vertex
    valley = p.edges[p.assignments == "V"]
    assert 10 <= len(valley) <= 60 < (drawn.assignments == "V").sum()
    chords = p.vertices[valley]
    assert np.hypot(*(chords[:, 1] - chords[:, 0]).T).max() <= interval
    dense = drawn.vertices[np.unique(drawn.edges[drawn.assignments == "V"])]
    kept_v = {tuple(q) for q in np.round(p.vertices[np.unique(valley)], 9).tolist()}
    assert kept_v <= {tuple(q) for q in np.round(dense, 9).tolist()}  # drawn vertices, nothing moved
    a, b = chords[:, 0], chords[:, 1]
    gaps = [_point_segment_gap(q, a, b) for q in dense]
    assert max(gaps) <= tolerance * (1 + 1e-9)
    assert p.edge_from_curve[p.assignments == "V"].all()
    crossing = p.vertices[np.unique(p.edges[p.assignments == "M"])]
    assert len(crossing) == 3  # the mountain's ends and where it crosses the valley
    alone = tmp_path / "alone.svg"
    alone.write_text(_dense_arc_svg(0.05, 2, crossed=False))
    report = fold_pattern(read_pattern(alone)).report
    assert report["converged"] and report["fold_angle_error_mean_deg"] < 5.0
    # the paper's own sampling (our SVG export of a Bézier) is left as it is
    exact = tmp_path / "exact.svg"
    exact.write_text(_dense_arc_svg(interval * 0.9, None))
    kept = read_pattern(exact)
    assert (kept.assignments == "V").sum() == (read_pattern(exact, interval=0.01).assignments == "V").sum()


def _point_segment_gap(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Distance of point ``q`` from the nearest of the segments ``a[k]``–``b[k]``."""
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", q - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
    return float(np.min(np.hypot(*(q - (a + t[:, None] * ab)).T)))
