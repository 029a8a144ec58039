"""Self-intersection report (issue 17): crossing triangles of a folded sheet, ``core.metrics.intersections``.

Checked against an independent brute force (every edge of one triangle against the other triangle,
Möller–Trumbore), on real folds (flaps that cross, ``examples/single_curve.svg`` that does not) and for speed.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from curved_fold.core.metrics.intersections import count_intersecting_faces, intersecting_faces, intersecting_pairs

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

CROSSING_FLAPS = """<?xml version="1.0" encoding="utf-8"?>
<svg xmlns="http://www.w3.org/2000/svg" width="110mm" height="60mm" viewBox="0 0 110 60">
  <rect x="0" y="0" width="110" height="60" fill="none" stroke="#000000"/>
  <path d="M 40 0 C 44 20 44 40 40 60" fill="none" stroke="#0000ff" opacity="0.9"/>
  <path d="M 70 0 C 66 20 66 40 70 60" fill="none" stroke="#0000ff" opacity="0.9"/>
</svg>
"""
"""Two curved valley creases 30 mm apart with 40 mm flaps, 162°: past about 90 % the flaps pass through each other
above the middle panel; at 50 % (81°) they stand apart."""


def _segment_hits(p0: np.ndarray, p1: np.ndarray, tri: np.ndarray, eps: float = 1e-9) -> np.ndarray:
    """Segments ``p0→p1`` ``(k, 3)`` crossing the interior of triangles ``tri`` ``(k, 3, 3)`` (Möller–Trumbore)."""
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    d = p1 - p0
    h = np.cross(d, e2)
    det = np.einsum("kj,kj->k", e1, h)
    ok = np.abs(det) > eps
    inv = 1.0 / np.where(ok, det, 1.0)
    s = p0 - tri[:, 0]
    u = inv * np.einsum("kj,kj->k", s, h)
    q = np.cross(s, e1)
    v = inv * np.einsum("kj,kj->k", d, q)
    t = inv * np.einsum("kj,kj->k", e2, q)
    return ok & (u > eps) & (v > eps) & (u + v < 1 - eps) & (t > eps) & (t < 1 - eps)


def _brute_pairs(x: np.ndarray, tris: np.ndarray) -> set[tuple[int, int]]:
    """Every non-adjacent pair where an edge of one triangle passes through the other (general position)."""
    a, b = np.triu_indices(len(tris), 1)
    far = ~np.any(tris[a][:, :, None] == tris[b][:, None, :], axis=(1, 2))
    a, b = a[far], b[far]
    hit = np.zeros(len(a), dtype=bool)
    for first, second in ((a, b), (b, a)):
        for i, j in ((0, 1), (1, 2), (2, 0)):
            hit |= _segment_hits(x[tris[first, i]], x[tris[first, j]], x[tris[second]])
    return set(zip(a[hit].tolist(), b[hit].tolist(), strict=True))


@pytest.mark.parametrize("seed", range(6))
def test_random_triangles_match_brute_force(seed):
    rng = np.random.default_rng(seed)
    n = 120
    centres = rng.uniform(0, 10, (n, 3))
    x = (centres[:, None, :] + rng.normal(0, 1.2, (n, 3, 3))).reshape(-1, 3)
    tris = np.arange(3 * n).reshape(n, 3)
    # a few shared corners so the adjacency exclusion is exercised
    tris[1::7, 0] = tris[0::7, 0][: len(tris[1::7])]
    got = set(map(tuple, intersecting_pairs(x, tris).tolist()))
    want = _brute_pairs(x, tris)
    assert len(want) > 20  # the soup is dense enough to test something
    assert got == want


def test_neighbours_touching_and_coplanar_layers_are_not_crossings():
    # two triangles sharing a vertex and passing through each other: neighbours in the sheet, excluded
    x = np.array([[0, 0, 0], [4, 0, 0], [0, 4, 0], [2, 1, -1], [1, 2, 1], [0, 0, 0]], float)
    assert len(intersecting_pairs(x, np.array([[0, 1, 2], [0, 3, 4]]))) == 0
    # the same two without the shared vertex (index 5 sits where 0 is) cross
    assert intersecting_pairs(x, np.array([[0, 1, 2], [5, 3, 4]])).tolist() == [[0, 1]]
    # a corner resting on a face, and two coplanar overlapping layers: contact, not penetration
    touch = np.array([[0, 0, 0], [4, 0, 0], [0, 4, 0], [1, 1, 0], [1, 1, 3], [2, 1, 3]], float)
    assert len(intersecting_pairs(touch, np.array([[0, 1, 2], [3, 4, 5]]))) == 0
    layers = np.array([[0, 0, 0], [4, 0, 0], [0, 4, 0], [0.5, 0.5, 0], [2.5, 0.5, 0], [0.5, 2.5, 0]], float)
    assert len(intersecting_pairs(layers, np.array([[0, 1, 2], [3, 4, 5]]))) == 0
    # lift one layer through the other by a tilt: now it crosses
    layers[4, 2] = 1.0
    layers[3, 2] = -1.0
    assert count_intersecting_faces(layers, np.array([[0, 1, 2], [3, 4, 5]])) == 2


def _rolled_sheet(n: int, turns: float) -> tuple[np.ndarray, np.ndarray]:
    """A ``2 n²``-triangle grid rolled into a spiral of ``turns`` (never touching itself) with a wave along it."""
    u, v = (g.ravel() for g in np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="ij"))
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    tris = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    angle, radius = 2 * np.pi * turns * u, 100 * (1 - 0.25 * u)
    x = np.column_stack([radius * np.cos(angle), radius * np.sin(angle), 200 * v + 5 * np.sin(12 * u)])
    return x, tris


def test_rolled_sheet_none_then_pushed_through_itself():
    x, tris = _rolled_sheet(30, 1.6)
    assert count_intersecting_faces(x, tris) == 0
    # push the inner end of the spiral (u > 0.9, radius 77 mm) out through the turn before it (u ≈ 0.28, 93 mm):
    # faces are found crossing at both places, and none elsewhere
    u = np.repeat(np.linspace(0, 1, 31), 31)
    pushed = x.copy()
    pushed[:, :2] *= np.where(u > 0.91, 1.4, 1.0)[:, None]
    crossing = intersecting_faces(pushed, tris)
    corner_u = u[tris]
    assert crossing[(corner_u > 0.85).all(axis=1)].any() and crossing[(corner_u < 0.4).all(axis=1)].any()
    assert not crossing[((corner_u > 0.4) & (corner_u < 0.85)).all(axis=1)].any()
    assert not crossing[(corner_u < 0.15).all(axis=1)].any()


def test_5000_faces_under_50_ms():
    x, tris = _rolled_sheet(50, 1.6)
    assert len(tris) == 5000
    intersecting_pairs(x, tris)
    best = min(_cpu_ms(lambda: intersecting_pairs(x, tris)) for _ in range(5))
    assert best <= 50.0, f"self-intersection of 5000 faces took {best:.1f} ms (CPU)"


def _cpu_ms(f) -> float:
    t0 = time.process_time()
    f()
    return (time.process_time() - t0) * 1000.0


def test_report_crossing_flaps_and_single_curve(tmp_path):
    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.pipeline import fold_pattern

    svg = tmp_path / "crossing_flaps.svg"
    svg.write_text(CROSSING_FLAPS)
    crossing = read_pattern(svg)
    folded = fold_pattern(crossing, percent=1.0).report
    assert folded["converged"] and folded["self_intersecting_faces"] > 0
    assert fold_pattern(crossing, percent=0.5).report["self_intersecting_faces"] == 0
    single = fold_pattern(read_pattern(EXAMPLES / "single_curve.svg"), percent=1.0).report
    assert single["converged"] and single["self_intersecting_faces"] == 0


def test_cli_prints_and_writes_the_count(tmp_path, capsys):
    import json

    from curved_fold.cli import main

    svg = tmp_path / "crossing_flaps.svg"
    svg.write_text(CROSSING_FLAPS)
    report = tmp_path / "r.json"
    assert main(["fold", str(svg), "--out", str(tmp_path / "o.fold"), "--report", str(report)]) == 0
    count = json.loads(report.read_text())["self_intersecting_faces"]
    assert count > 0
    assert f"self-intersection: {count} faces" in capsys.readouterr().out


def test_chunked_broad_phase_finds_the_same_pairs(monkeypatch):
    """Crowded cells are processed in bounded chunks (memory of stacked layers); the pairs do not depend on it."""
    from curved_fold.core.metrics import intersections

    x, tris = _rolled_sheet(20, 1.6)
    x[:, :2] *= np.where(np.repeat(np.linspace(0, 1, 21), 21) > 0.91, 1.4, 1.0)[:, None]
    whole = intersecting_pairs(x, tris)
    monkeypatch.setattr(intersections, "CHUNK_PAIRS", 7)
    assert len(whole) and np.array_equal(intersecting_pairs(x, tris), whole)


def test_the_test_comes_in_units_for_a_blender_job():
    """A Blender job runs the test one unit per slice (a 4,128-face pleat folded to 180° took 147–154 ms in one
    call): units of a bounded number of candidate pairs, the same crossing triangles."""
    from curved_fold.core import run_to_end
    from curved_fold.core.metrics import intersections

    x, tris = _rolled_sheet(20, 1.6)
    x[:, :2] *= np.where(np.repeat(np.linspace(0, 1, 21), 21) > 0.91, 1.4, 1.0)[:, None]
    whole = intersecting_faces(x, tris)
    steps = intersections.intersecting_faces_steps(x, tris, chunk_pairs=50)
    units = 0
    while True:
        try:
            next(steps)
        except StopIteration as done:
            mask = done.value
            break
        units += 1
    assert whole.any() and units >= 10 and np.array_equal(mask, whole)
    assert np.array_equal(run_to_end(intersections.intersecting_faces_steps(x, tris)), whole)
