"""The exact folded shapes in tests/analytic.py are isometries with the stated fold angle (ground-truth §3.2–3.4)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.analytic import annular_sector, bisector_case, parabola_strip


def _dihedral(p: np.ndarray, a: int, b: int, c: int, d: int) -> float:
    """Signed fold angle (deg) across edge a→b with CCW triangles (a, b, c) and (b, a, d); valley > 0."""
    e = (p[b] - p[a]) / np.linalg.norm(p[b] - p[a])
    n1 = np.cross(p[b] - p[a], p[c] - p[a])
    n2 = np.cross(p[a] - p[b], p[d] - p[b])
    n1 /= np.linalg.norm(n1)
    n2 /= np.linalg.norm(n2)
    return float(np.degrees(np.arctan2(np.dot(np.cross(n1, e), n2), np.dot(n1, n2))))


def _edge_lengths(pts: np.ndarray, tris: np.ndarray) -> np.ndarray:
    pairs = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    return np.linalg.norm(pts[pairs[:, 0]] - pts[pairs[:, 1]], axis=1)


@pytest.mark.parametrize("rho", [120.0, -75.0, 30.0])
def test_bisector_case_is_isometric_with_exact_fold_angle(rho: float) -> None:
    case = bisector_case(n_segments=24, fold_angle_deg=rho)
    tris = case.ideal_triangles()
    flat = case.pattern.vertices
    v = flat[tris]
    area = (v[:, 1, 0] - v[:, 0, 0]) * (v[:, 2, 1] - v[:, 0, 1]) - (v[:, 1, 1] - v[:, 0, 1]) * (v[:, 2, 0] - v[:, 0, 0])
    assert np.all(area > 0)
    assert len(tris) == 4 * case.n_segments
    folded = case.folded_positions()
    flat3 = np.column_stack([flat, np.zeros(len(flat))])
    assert np.max(np.abs(_edge_lengths(folded, tris) - _edge_lengths(flat3, tris))) < 1e-12
    # the folded state is far from flat (the test would pass trivially otherwise)
    assert np.ptp(folded[:, 2]) > 5.0
    n = case.n_segments
    for i in range(n):  # crease edge c_i → c_{i+1}: left triangle (c_i, c_{i+1}, L_{i+1}), right (c_{i+1}, c_i, R_i)
        ang = _dihedral(folded, i, i + 1, n + 2 + i, 2 * n + 2 + i)
        assert ang == pytest.approx(rho, abs=1e-9)
    # bisector edges present in the ideal mesh
    sides = {tuple(sorted(p)) for t in tris for p in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    assert case.bisector_edges <= sides
    assert len(case.bisector_edges) == 2 * (n - 1)


def test_bisector_case_pattern_is_consistent() -> None:
    case = bisector_case(n_segments=12)
    case.pattern.validate()
    assert case.pattern.count("V") == 12
    assert case.pattern.count("B") == 2 * 12 + 4
    assert np.all(case.pattern.edge_from_curve == (case.pattern.assignments == "V"))


def _jacobian_error(fn, pts: np.ndarray, h: float = 1e-4) -> float:
    """max |JᵀJ − I| of the map at the points, by central differences."""
    ex = np.array([h, 0.0])
    ey = np.array([0.0, h])
    jx = (fn(pts + ex) - fn(pts - ex)) / (2 * h)
    jy = (fn(pts + ey) - fn(pts - ey)) / (2 * h)
    g = np.stack(
        [
            np.einsum("ij,ij->i", jx, jx) - 1,
            np.einsum("ij,ij->i", jy, jy) - 1,
            np.einsum("ij,ij->i", jx, jy),
        ]
    )
    return float(np.max(np.abs(g)))


def _strip_points(strip, k: int = 9) -> np.ndarray:
    xs = np.linspace(-0.9 * strip.half_width, 0.9 * strip.half_width, k)
    ws = np.linspace(-0.9 * strip.width, 0.9 * strip.width, k)
    ws = ws[np.abs(ws) > 0.5]  # keep off the crease (|w| is not differentiable there)
    xx, ww = np.meshgrid(xs, ws)
    x, w = xx.ravel(), ww.ravel()
    c = strip.crease_point(x)
    t = np.column_stack([np.ones_like(x), x / strip.p]) / np.sqrt(1 + (x / strip.p) ** 2)[:, None]
    return c + w[:, None] * np.column_stack([-t[:, 1], t[:, 0]])


@pytest.mark.parametrize("rho", [108.0, -60.0])
def test_parabola_strip_closed_form_is_isometric(rho: float) -> None:
    strip = parabola_strip(p=60.0, width=20.0, fold_angle_deg=rho)
    pts = _strip_points(strip)
    assert _jacobian_error(strip.exact_positions, pts) < 1e-6
    P = strip.exact_positions(pts)
    assert np.sign(P[:, 2]).mean() == pytest.approx(np.sign(rho))
    # crease: unit-speed in the flat arc length, tangent angle = flat tangent angle / cos(rho/2) (k = κ cos α)
    x = np.linspace(-50, 50, 11)
    hx = 1e-5
    dX = (strip.crease_3d(x + hx)[0] - strip.crease_3d(x - hx)[0]) / (2 * hx)
    assert np.allclose(np.linalg.norm(dX, axis=1), np.sqrt(1 + (x / strip.p) ** 2), rtol=1e-8)
    assert np.allclose(np.arctan2(dX[:, 1], dX[:, 0]), np.arctan(x / strip.p) / np.cos(np.radians(rho) / 2), atol=1e-8)
    h = 1e-3
    for x0 in (-30.0, 0.0, 45.0):
        base = strip.crease_point(np.array([x0]))[0]
        t = np.array([1.0, x0 / strip.p]) / np.hypot(1.0, x0 / strip.p)
        n2 = np.array([-t[1], t[0]])
        q = np.array([base - h * t, base + h * t, base + 5 * h * n2, base - 5 * h * n2])
        Q = strip.exact_positions(q)
        ang = _dihedral(Q, 0, 1, 2, 3)
        assert ang == pytest.approx(rho, abs=1e-3)


def test_parabola_strip_curves_describe_the_strip() -> None:
    strip = parabola_strip(p=60.0, width=20.0)
    assert [c.assignment for c in strip.curves] == ["V", "B", "B", "B", "B"]
    crease = strip.curves[0].segments[0]
    t = np.linspace(0, 1, 11)
    pts = crease.evaluate(t)
    assert np.allclose(pts[:, 1], pts[:, 0] ** 2 / 120.0, atol=1e-12)  # a cubic that IS the parabola
    for border in strip.curves[1:3]:
        for seg in border.segments:
            x, w = strip.flat_coordinates(seg.evaluate(t))
            assert np.allclose(np.abs(w), 20.0, atol=0.02)  # C¹ cubic chain close to the exact offset


@pytest.mark.parametrize("rho", [108.0, -140.0])
def test_annular_sector_closed_form(rho: float) -> None:
    sec = annular_sector(40.0, 70.0, 100.0, 90.0, rho)
    r = np.linspace(42, 98, 8)
    r = r[np.abs(r - 70) > 1]
    th = np.radians(np.linspace(-40, 40, 7))
    rr, tt = np.meshgrid(r, th)
    pts = np.column_stack([(rr * np.cos(tt)).ravel(), (rr * np.sin(tt)).ravel()])
    assert _jacobian_error(sec.exact_positions, pts) < 1e-6
    crease = sec.exact_positions(np.column_stack([70 * np.cos(th), 70 * np.sin(th)]))
    assert np.allclose(np.hypot(crease[:, 0], crease[:, 1]), 70 * np.cos(np.radians(rho) / 2))
    # discrete form: radial-line mesh keeps every edge length exactly, crease dihedral = rho
    n = 12
    thj = np.radians(-45 + 90 * np.arange(n + 1) / n)
    radii = np.array([40.0, 70.0, 100.0])
    flat = np.array([[rad * np.cos(a), rad * np.sin(a)] for rad in radii for a in thj])
    P = sec.discrete_positions(flat, n)
    idx = np.arange(3 * (n + 1)).reshape(3, n + 1)
    tris = []
    for k in range(2):
        for j in range(n):
            a, b, c, d = idx[k, j], idx[k, j + 1], idx[k + 1, j + 1], idx[k + 1, j]
            tris += [(a, b, c), (a, c, d)]
    tris = np.array(tris)
    flat3 = np.column_stack([flat, np.zeros(len(flat))])
    assert np.max(np.abs(_edge_lengths(P, tris) - _edge_lengths(flat3, tris))) < 1e-11
    j = 5  # crease edge a → b runs CCW about the origin: the inner triangle is on its left
    a, b = idx[1, j], idx[1, j + 1]
    ang = _dihedral(P, a, b, idx[0, j], idx[2, j + 1])
    assert ang == pytest.approx(rho, abs=1e-9)


def test_annular_sector_curves() -> None:
    sec = annular_sector()
    assert [c.assignment for c in sec.curves] == ["V", "B", "B", "B", "B"]
    arc = sec.curves[0].segments[0]
    pts = arc.evaluate(np.linspace(0, 1, 5))
    assert np.allclose(np.hypot(pts[:, 0], pts[:, 1]), 70.0)
    with pytest.raises(ValueError, match="overlaps"):
        annular_sector(theta_deg=300.0, fold_angle_deg=150.0)
