"""Long straight creases split where the triangulation would fan needles off them (``core/mesh/needles.py``).

Two drawings by helper sessions (thirteenth pass), both with the needles before this split:
``tests/data/sine_across_pleats.svg`` (24 straight 200 mm pleats crossed at shallow angles by two sine creases: 43
corners under 1°, down to 0.03°, 159 iterations to the round-off floor at 100 %) and
``tests/data/strip_stopping_short.svg`` (a 1,000 × 50 mm strip with short cross creases stopping 4 mm from its centre
valley: not converged in 500 iterations, residual 1.6).
"""

from __future__ import annotations

import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from curved_fold.core.io.reader import read_pattern
from curved_fold.core.mesh.build import build_mesh
from curved_fold.core.mesh.fold_mesh import corner_angles
from curved_fold.core.mesh.needles import NEEDLE_DEG, split_needle_creases
from curved_fold.core.mesh.triangulate import constrained_triangulation
from curved_fold.core.pattern.discretize import default_parameters
from curved_fold.core.pipeline import fold_pattern

DATA = Path(__file__).resolve().parent / "data"
FIXTURES = Path(__file__).resolve().parent / "fixtures" / "origami-simulator"


@pytest.fixture(scope="module")
def sine() -> object:
    return read_pattern(DATA / "sine_across_pleats.svg")


def _corners(mesh) -> np.ndarray:
    return corner_angles(mesh.vertices, mesh.triangles)


def test_needles_beside_long_straight_creases_are_gone(sine) -> None:
    """Whole, the pleats fan 43 corners under 1° (down to 0.03°); split where they bound a needle, none is left, and
    the pieces are the pleats themselves: each lies on its drawn line, keeps its stroke, role and fold angle, and
    is no longer than the interval."""
    whole = _corners(build_mesh(replace(sine, interval=math.inf)))
    assert whole.min() < 0.05 and np.count_nonzero(whole < NEEDLE_DEG) >= 40
    split, _ = split_needle_creases(sine)
    mesh = build_mesh(sine)
    assert _corners(mesh).min() >= NEEDLE_DEG
    added = split.n_edges - sine.n_edges
    assert added > 100
    # edge k's first piece stays edge k; the new pieces follow, each on a straight crease of its own stroke
    v, v0 = split.vertices, sine.vertices
    for k in range(sine.n_edges, split.n_edges):
        assert split.assignments[k] in ("M", "V") and not split.edge_from_curve[k]
        a, b = v[split.edges[k]]
        assert np.linalg.norm(b - a) <= sine.interval * (1 + 1e-9)
        mine = np.flatnonzero((sine.edge_polyline == split.edge_polyline[k]) & ~sine.edge_from_curve)
        p, q = v0[sine.edges[mine, 0]], v0[sine.edges[mine, 1]]
        d = q - p
        off = [np.abs(d[:, 0] * (x[1] - p[:, 1]) - d[:, 1] * (x[0] - p[:, 0])) / np.hypot(*d.T) for x in (a, b)]
        along = [((x - p) * d).sum(axis=1) / (d * d).sum(axis=1) for x in (a, b)]
        on = (off[0] < 1e-9) & (off[1] < 1e-9)
        on &= (along[0] > -1e-12) & (along[0] < 1 + 1e-12) & (along[1] > -1e-12) & (along[1] < 1 + 1e-12)
        assert on.any(), f"piece {k} lies on no straight crease of its stroke"
    same = np.array([split.edge_polyline[k] == sine.edge_polyline[k] for k in range(sine.n_edges)])
    assert same.all() and np.array_equal(split.fold_angles[: sine.n_edges], sine.fold_angles, equal_nan=True)


def test_the_split_folds_the_sine_across_pleats_quickly(sine) -> None:
    """At 100 %: 159 iterations to the round-off floor with the needles; split, a converged minimum in a few tens."""
    report = fold_pattern(sine, percent=1.0).report
    assert report["converged"] and not report["converged_to_round_off"], report["message"]
    assert report["negative_pivots"] == 0 and report["iterations"] <= 40


@pytest.mark.parametrize("percent", [0.6, 1.0])
def test_a_strip_with_creases_stopping_short_of_its_centre_folds(percent: float) -> None:
    """The 1,000 mm valley was one segment; the short mountains' free ends 4 mm beside it fanned needles 500 mm
    long (corners 0.09°), and the fold stopped at 500 iterations, residual 1.6. Split, it converges."""
    pattern = read_pattern(DATA / "strip_stopping_short.svg")
    whole = _corners(build_mesh(replace(pattern, interval=math.inf)))
    run = fold_pattern(pattern, percent=percent)
    assert whole.min() < 0.5 and _corners(run.mesh).min() > 1.0
    assert run.report["converged"] and run.report["negative_pivots"] == 0, run.report["message"]
    assert run.report["iterations"] <= 60


def test_patterns_without_needles_are_left_as_drawn() -> None:
    """No needle, no split: the same pattern object and the plain constrained triangulation (every fixture but
    huffmanTower; its mesh digests were re-recorded for the split)."""
    for name in ("CircularPleat-antiFacet", "Carved_Cylinder", "miura-ori", "curvedPleatSimple", "shell14"):
        pattern = read_pattern(FIXTURES / f"{name}.svg")
        split, pt = split_needle_creases(pattern)
        assert split is pattern, name
        assert np.array_equal(pt.triangles, constrained_triangulation(pattern).triangles), name
    huffman = read_pattern(FIXTURES / "huffmanTower.svg")
    assert split_needle_creases(huffman)[0].n_edges > huffman.n_edges


def test_the_earcut_baseline_keeps_straight_creases_whole(sine) -> None:
    """Origami Simulator's own mesh (the ``earcut`` baseline) has no such split: its vertices are the pattern's."""
    mesh = build_mesh(sine, "earcut")
    assert mesh.n_vertices == sine.n_vertices and _corners(mesh).min() < 0.1


def test_a_pattern_read_as_segments_is_split_at_its_sheets_default_interval(sine) -> None:
    """A FOLD file's pattern has no interval of its own (nan): the paper's, scaled to the sheet, applies; an infinite
    one keeps every crease whole."""
    assert sine.interval == default_parameters(200.0)[0]  # the drawing was sampled at the default
    split, _ = split_needle_creases(replace(sine, interval=math.nan))
    assert split.n_edges > sine.n_edges
    assert np.array_equal(split.vertices, split_needle_creases(sine)[0].vertices)
    assert split_needle_creases(replace(sine, interval=math.inf))[0].n_edges == sine.n_edges


def _pleats(tmp_path: Path, count: int, gap: float, *, arc: bool, length: float = 200.0):
    """``count`` parallel straight pleats ``gap`` mm apart across a sheet ``length`` mm wide, with (``arc``) a shallow
    curve 1 mm beside the first (a helper's review drawings, fourteenth pass)."""
    lines = []
    for k in range(1, count + 1):
        colour = "#0000ff" if k % 2 else "#ff0000"
        lines.append(f'<path id="p{k}" d="M 0 {k * gap} L {length} {k * gap}" stroke="{colour}" opacity="0.5"/>')
    if arc:
        lines.append(
            f'<path id="arc" d="M {0.2 * length} {gap - 1} Q {0.5 * length} {gap - 4} {0.8 * length} {gap - 1}" '
            'stroke="#0000ff" opacity="0.3"/>'
        )
    return _sheet(tmp_path / f"pleats_{count}_{gap}_{arc}.svg", lines, length, gap * (count + 1))


def _sheet(path: Path, body: list[str], width: float = 200.0, height: float = 200.0):
    """The pattern of an SVG sheet ``width`` × ``height`` mm (its border drawn) with the elements ``body``, written
    to ``path``."""
    border = f'<path id="border" d="M 0 0 L {width} 0 L {width} {height} L 0 {height} Z" fill="none" stroke="#000000"/>'
    path.write_text(
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}mm" height="{height}mm" '
        f'viewBox="0 0 {width} {height}">' + border + "".join(body) + "</svg>"
    )
    return read_pattern(path)


def test_a_cut_beside_a_crease_is_split_too(tmp_path: Path) -> None:
    """A straight cut 1 mm beside a long valley, a shallow arc beside both (a review session's kirigami drawing,
    fourteenth pass): with the cut whole, the split valley's vertices fanned needles to its far ends (corners down to
    0.1°); split as creases are, none is left, and the mesh is cut open along every piece."""
    body = [
        '<path id="s1" d="M 0 90 L 300 90" stroke="#ff0000" opacity="0.5"/>',
        '<path id="cut" d="M 60 91 L 240 91" stroke="#00ff00"/>',
        '<path id="a0" d="M 40 88.8 A 3000 3000 0 0 1 260 88.8" fill="none" stroke="#0000ff" opacity="0.3"/>',
    ]
    pattern = _sheet(tmp_path / "cut.svg", body, 300.0, 120.0)
    whole = build_mesh(replace(pattern, interval=math.inf))
    assert _corners(whole).min() < 0.5
    mesh = build_mesh(pattern)
    assert _corners(mesh).min() > NEEDLE_DEG
    split, _ = split_needle_creases(pattern)
    pieces = np.count_nonzero(split.assignments == "C")
    assert pieces == math.ceil(180.0 / pattern.interval)
    # both sides of every piece are border edges of the mesh: the sheet is cut along the whole of it (SVG y is down)
    v, e = mesh.vertices * [1.0, -1.0], mesh.edges
    on_cut = np.all(np.isclose(v[e][:, :, 1], 91.0), axis=1) & np.all(
        (v[e][:, :, 0] > 59.9) & (v[e][:, :, 0] < 240.1), axis=1
    )
    assert np.count_nonzero(on_cut) == 2 * pieces and np.all(mesh.assignments[on_cut] == "B")
    run = fold_pattern(pattern, percent=1.0)
    assert run.result.converged and run.report["corners_below_1deg"] == 0


def test_a_hypar_folds_closer_to_its_angles_split(tmp_path: Path) -> None:
    """A hypar (20 concentric squares 5 mm apart, valley diagonals) has straight creases only, and its trapezoids
    bend: whole, they fanned needles (0.32°) and at 100 % the fold missed its angles by 46° on average at 2.8 %
    strain; split, by 11° at 0.9 % (a review session's drawing; the revision that left faces of straight creases
    alone whole brought the 46° back)."""
    body = []
    for k in range(1, 20):
        lo, hi = 100 - 5 * k, 100 + 5 * k
        colour = "#ff0000" if k % 2 else "#0000ff"
        body.append(
            f'<path id="sq{k}" d="M {lo} {lo} L {hi} {lo} L {hi} {hi} L {lo} {hi} Z" fill="none" '
            f'stroke="{colour}" opacity="0.5"/>'
        )
    body += [
        '<path id="d1" d="M 0 0 L 200 200" stroke="#0000ff" opacity="0.5"/>',
        '<path id="d2" d="M 200 0 L 0 200" stroke="#0000ff" opacity="0.5"/>',
    ]
    pattern = _sheet(tmp_path / "hypar.svg", body)
    whole = fold_pattern(replace(pattern, interval=math.inf), percent=1.0).report
    split = fold_pattern(pattern, percent=1.0).report
    assert whole["smallest_corner_deg"] < 0.5 and split["smallest_corner_deg"] > 10.0
    assert split["converged"] and split["negative_pivots"] == 0, split["message"]
    assert split["fold_angle_error_mean_deg"] < 0.4 * whole["fold_angle_error_mean_deg"]
    assert split["strain_mean_pct"] < 0.5 * whole["strain_mean_pct"]


def test_a_split_is_carried_across_thin_strips_only(tmp_path: Path) -> None:
    """Marked, a crease carries its split to the creases parallel to it across thin strips (4 mm wide, 200 mm
    long), not across wide faces (100 mm between two verticals): a grid of squares carried 24 marked creases to
    5,001 before the strips had to be thin (a review session's drawing)."""
    import curved_fold.core.mesh.needles as needles

    body = [f'<path id="h{y}" d="M 0 {y} L 200 {y}" stroke="#ff0000" opacity="0.5"/>' for y in (100, 104, 108)]
    body += [f'<path id="v{x}" d="M {x} 120 L {x} 200" stroke="#0000ff" opacity="0.5"/>' for x in (50, 150)]
    pattern = _sheet(tmp_path / "strips.svg", body)
    pt = constrained_triangulation(pattern)
    v, e = pattern.vertices, pattern.edges
    horizontal = np.abs(v[e[:, 0], 1] - v[e[:, 1], 1]) < 1e-9
    eligible = pattern.assignments != "B"
    start = np.zeros(len(e), bool)
    start[np.flatnonzero(horizontal & (np.abs(v[e[:, 0], 1] + 100) < 1e-9))[0]] = True
    grown = needles._across_strips(pattern, pt, start, eligible)
    assert set(np.round(v[e[grown, 0], 1], 6).tolist()) == {-100.0, -104.0, -108.0} and horizontal[grown].all()
    start = np.zeros(len(e), bool)
    start[np.flatnonzero(~horizontal & (np.abs(v[e[:, 0], 0] - 50) < 1e-9))[0]] = True
    assert np.array_equal(needles._across_strips(pattern, pt, start, eligible), start)


def test_a_split_is_carried_across_parallel_strips_in_one_round(tmp_path: Path, monkeypatch) -> None:
    """An arc 1 mm beside the first of 40 pleats 5 mm apart: split on one side only, each strip fanned from its
    whole side's ends (a needle the next round split: one triangulation per strip, and at 120 pleats the 64-round
    cap). Carried across the strips, every pleat is split in one round and no needle is left."""
    import curved_fold.core.mesh.needles as needles

    calls = []
    real = needles.constrained_triangulation
    monkeypatch.setattr(needles, "constrained_triangulation", lambda *a, **k: calls.append(1) or real(*a, **k))
    pattern = _pleats(tmp_path, 40, 5.0, arc=True)
    split, pt = split_needle_creases(pattern)
    assert len(calls) == 2
    assert corner_angles(pt.vertices, pt.triangles).min() >= NEEDLE_DEG
    pleat = ~split.edge_from_curve & (split.assignments != "B")
    pieces = np.linalg.norm(split.vertices[split.edges[pleat, 1]] - split.vertices[split.edges[pleat, 0]], axis=1)
    assert pieces.max() <= pattern.interval * (1 + 1e-9)


def test_the_split_keeps_within_the_segment_budget(sine, monkeypatch) -> None:
    """Split at the interval, the pieces may not take a pattern past the discretisation's segment budget: the split
    is then made at a larger interval, and a warning says so."""
    import curved_fold.core.mesh.needles as needles

    budget = sine.n_edges + 120
    monkeypatch.setattr(needles, "MAX_SEGMENTS", budget)
    split, _ = split_needle_creases(sine)
    assert sine.n_edges < split.n_edges <= budget
    [note] = [w for w in split.warnings if "would make more than" in w]
    assert note.startswith("meshing: splitting ") and f"more than {budget} segments; split at " in note


def test_no_split_when_the_segment_budget_is_spent(sine, monkeypatch) -> None:
    """A pattern already at the segment budget gets no split, a warning, and no endless search for an interval (a
    review session's 205,000-segment grid hung there)."""
    import curved_fold.core.mesh.needles as needles

    monkeypatch.setattr(needles, "MAX_SEGMENTS", sine.n_edges)
    split, _ = split_needle_creases(sine)
    assert split.n_edges == sine.n_edges
    assert any("were not split: the pattern already has 229 segments (limit 229)" in w for w in split.warnings)


def test_the_budget_warnings_name_cuts_as_cuts(sine, monkeypatch) -> None:
    """Straight cuts beside needles are split as creases are; the budget's warnings count them as cuts."""
    import curved_fold.core.mesh.needles as needles

    straight = np.flatnonzero(~sine.edge_from_curve & (sine.assignments != "B"))
    assignments = sine.assignments.copy()
    assignments[straight[::2]] = "C"
    cut = replace(sine, assignments=assignments)
    monkeypatch.setattr(needles, "MAX_SEGMENTS", cut.n_edges)
    [note] = [w for w in split_needle_creases(cut)[0].warnings if "were not split" in w]
    assert re.match(r"meshing: \d+ straight crease\(s\) and \d+ straight cut\(s\) beside needles were not", note)
    monkeypatch.setattr(needles, "MAX_SEGMENTS", cut.n_edges + 120)
    [note] = [w for w in split_needle_creases(cut)[0].warnings if "would make more than" in w]
    assert re.match(r"meshing: splitting \d+ straight crease\(s\) and \d+ straight cut\(s\) beside needles", note)


def test_a_fold_file_keeps_the_interval_its_creases_were_split_at(sine, tmp_path: Path) -> None:
    """Folded at a 40 mm interval and written as FOLD (the folded mesh, or the crease pattern), the file keeps the
    interval (``curved_fold:interval``), so it reads back to the same mesh: at the sheet's default it was split
    again (394 → 790 faces; a review session's finding)."""
    from curved_fold.core.io.fold import pattern_for_folding, read_fold, write_folded_fold, write_pattern_fold

    coarse = read_pattern(DATA / "sine_across_pleats.svg", interval=40.0)
    mesh = build_mesh(coarse)
    folded, crease_pattern = tmp_path / "folded.fold", tmp_path / "pattern.fold"
    write_folded_fold(folded, mesh, [np.column_stack([mesh.vertices, np.zeros(mesh.n_vertices)])])
    write_pattern_fold(crease_pattern, coarse)
    in_metres = tmp_path / "folded_m.fold"  # the interval is written in the file's unit
    write_folded_fold(in_metres, mesh, [np.column_stack([mesh.vertices, np.zeros(mesh.n_vertices)])], unit="m")
    assert pattern_for_folding(read_fold(in_metres)).interval == pytest.approx(40.0, rel=1e-12)
    for path in (folded, crease_pattern, in_metres):
        again = build_mesh(pattern_for_folding(read_fold(path)))
        assert again.n_faces == mesh.n_faces and np.allclose(
            np.sort(again.vertices, axis=0), np.sort(mesh.vertices, axis=0)
        )


def test_needles_left_at_the_round_cap_are_reported(sine, monkeypatch) -> None:
    """With no round left to split them, the needles stay, and a warning gives the smallest corner."""
    import curved_fold.core.mesh.needles as needles

    monkeypatch.setattr(needles, "MAX_ROUNDS", 1)
    split, _ = split_needle_creases(sine)
    assert split.n_edges == sine.n_edges
    assert any(
        "needles are left beside long straight creases after 0 round(s) of splits (the mesh's smallest corner 0.03°)"
        in w
        for w in split.warnings
    ), split.warnings
