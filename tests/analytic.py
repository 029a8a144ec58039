"""Exact folded shapes for tests (ground-truth.md §3.2–3.4), as plain data shared by every helper's tests.

Three cases, each a small dataclass with the flat input and the exact folded geometry:

* :func:`bisector_case` (§3.4): a polyline crease (a sampled parabola) with boundary vertices at the feet of the
  discrete bisector normals. The mesh whose diagonals are exactly those bisectors folds *isometrically*; its exact
  folded shape is :meth:`BisectorCase.folded_positions`. The ruling-aware swaps must recover these bisector edges.
* :func:`parabola_strip` (§3.2): a parabola crease ``y = x²/(2p)`` drawn exactly (a quadratic Bézier raised to a
  cubic), its offset borders and end normals; :meth:`ParabolaStrip.exact_positions` evaluates the continuous closed
  form (3D crease by Gauss–Legendre quadrature) at any flat points.
* :func:`annular_sector` (§3.3): a circular crease in an annular sector (two glued cones), with the continuous closed
  form :meth:`AnnularSector.exact_positions`.

Conventions as in ``core.pattern``: millimetres, sheet in the XY plane, valley (fold angle > 0) folds toward +z,
mountain (< 0) toward −z. No pytest in this module: tests import it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from curved_fold.core.pattern.model import CreaseCurve, CreasePattern, CurveSegment

# Gauss–Legendre nodes on [-1, 1] used for the §3.2 crease integral (smooth integrand: 1e-13 with one panel per
# point for the widths used in tests).
_GL_X, _GL_W = np.polynomial.legendre.leggauss(48)


def _assignment(fold_angle_deg: float) -> str:
    return "V" if fold_angle_deg >= 0 else "M"


# ---------------------------------------------------------------------------------------------------------------
# §3.4 exact discrete solution: polyline crease with bisector rulings
# ---------------------------------------------------------------------------------------------------------------


@dataclass
class BisectorCase:
    """A polyline crease with boundary vertices at the bisector feet (ground-truth §3.4).

    Vertex layout (``n`` segments): crease ``c_i`` = ``i`` (0..n), left boundary ``L_i`` = ``n + 1 + i``,
    right boundary ``R_i`` = ``2n + 2 + i``. "Left" is the side of ``t`` rotated +90° (here, above the parabola).

    * ``pattern``: crease edges ``V``/``M`` with the fold angle (``edge_from_curve`` True), border edges ``B``;
      no diagonals.
    * ``bisector_edges``: the interior bisector edges ``(c_i, L_i)`` and ``(c_i, R_i)``, ``0 < i < n``, as sorted
      vertex pairs: the rulings the swaps must find.
    """

    pattern: CreasePattern
    bisector_edges: set[tuple[int, int]]
    crease_points: np.ndarray
    normals: np.ndarray
    width_left: float
    width_right: float
    n_segments: int
    fold_angle_deg: float

    @property
    def crease_vertices(self) -> np.ndarray:
        return np.arange(self.n_segments + 1)

    def ideal_triangles(self) -> np.ndarray:
        """A CCW triangulation containing every bisector edge (each quad split by its ``c_i``–``L/R_{i+1}`` diagonal).

        Any diagonal choice folds isometrically with :meth:`folded_positions`; this is the reference mesh for
        metric tests independent of the mesher.
        """
        n = self.n_segments
        tris = []
        for i in range(n):
            c0, c1 = i, i + 1
            l0, l1 = n + 1 + i, n + 2 + i
            r0, r1 = 2 * n + 2 + i, 2 * n + 3 + i
            tris += [(c0, c1, l1), (c0, l1, l0), (c0, r1, c1), (c0, r0, r1)]
        tris = np.array(tris, dtype=np.int64)
        v = self.pattern.vertices
        a, b, c = v[tris[:, 0]], v[tris[:, 1]], v[tris[:, 2]]
        area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
        flip = area < 0
        tris[flip] = tris[flip][:, [0, 2, 1]]
        return tris

    def folded_positions(self, rho_deg: float | None = None) -> np.ndarray:
        """The exact discrete folded shape ``(3n + 3, 3)`` at fold angle ``rho_deg`` (default: the pattern's).

        3D crease in z = 0 with the flat edge lengths and turning angles ``Θ_i = 2 atan(tan(θ_i/2) / cos γ)``,
        ``γ = ρ/2``; boundary vertices at ``X_i + W r_i`` with the §3.4 ruling images. Every triangle of any mesh
        made of the crease, the bisectors and quad diagonals keeps its edge lengths; crease dihedral = ρ.
        """
        rho = np.radians(self.fold_angle_deg if rho_deg is None else rho_deg)
        gamma = rho / 2.0
        c = self.crease_points
        d = np.diff(c, axis=0)
        lengths = np.hypot(d[:, 0], d[:, 1])
        phi = np.arctan2(d[:, 1], d[:, 0])
        turn = np.angle(np.exp(1j * np.diff(phi)))  # θ_i at interior vertices 1..n-1, wrapped to (-π, π]
        big_turn = 2.0 * np.arctan(np.tan(turn / 2.0) / np.cos(gamma))
        big_phi = phi[0] + np.concatenate([[0.0], np.cumsum(big_turn)])
        x = np.zeros((len(c), 3))
        x[0, :2] = c[0]
        x[1:, 0] = c[0, 0] + np.cumsum(lengths * np.cos(big_phi))
        x[1:, 1] = c[0, 1] + np.cumsum(lengths * np.sin(big_phi))

        # in-plane left normals of the 3D polyline (bisector at interior vertices, edge normal at the ends)
        half_turn = np.concatenate([[0.0], turn / 2.0, [0.0]])
        half_big = np.concatenate([[0.0], big_turn / 2.0, [0.0]])
        dir3 = np.concatenate([[big_phi[0]], big_phi[:-1] + big_turn / 2.0, [big_phi[-1]]]) + np.pi / 2.0
        m = np.column_stack([np.cos(dir3), np.sin(dir3), np.zeros(len(c))])
        y = np.sin(half_turn) * np.sin(half_big) + np.cos(half_turn) * np.cos(gamma) * np.cos(half_big)
        z = np.cos(half_turn) * np.sin(gamma)
        ez = np.array([0.0, 0.0, 1.0])
        left = x + self.width_left * (y[:, None] * m + z[:, None] * ez)
        right = x + self.width_right * (-y[:, None] * m + z[:, None] * ez)
        return np.concatenate([x, left, right])


def bisector_case(
    n_segments: int = 24,
    width_left: float = 20.0,
    width_right: float = 25.0,
    fold_angle_deg: float = 120.0,
    *,
    half_width: float = 75.0,
    focal: float = 60.0,
) -> BisectorCase:
    """The §3.4 test pattern: parabola ``y = x²/(2·focal)`` sampled at ``n_segments + 1`` equally spaced x in
    ``[-half_width, half_width]`` (150 mm wide by default), boundary vertices at the discrete bisector feet.

    ``width_left`` (the concave side, toward the focus) must stay below the discrete radius of curvature (≈ focal).
    """
    n = int(n_segments)
    if n < 2:
        raise ValueError(f"bisector_case: n_segments must be ≥ 2, got {n}")
    xs = np.linspace(-half_width, half_width, n + 1)
    c = np.column_stack([xs, xs**2 / (2.0 * focal)])
    d = np.diff(c, axis=0)
    # libm's atan2 and an exact wrap, not np.arctan2/np.angle(np.exp(1j·x)): their last bit depends on the numpy
    # version (and CPU), which changed this pattern, and so its meshes, between numpy 1.26 and 2
    phi = np.fromiter(map(math.atan2, d[:, 1].tolist(), d[:, 0].tolist()), dtype=float, count=len(d))
    dphi = np.diff(phi)
    turn = dphi - 2.0 * np.pi * np.round(dphi / (2.0 * np.pi))
    nd = np.concatenate([[phi[0]], phi[:-1] + turn / 2.0, [phi[-1]]]) + np.pi / 2.0
    normals = np.column_stack([np.cos(nd), np.sin(nd)])
    left = c + width_left * normals
    right = c - width_right * normals
    vertices = np.concatenate([c, left, right])

    crease = [(i, i + 1) for i in range(n)]
    border = [(n + 1 + i, n + 2 + i) for i in range(n)] + [(2 * n + 2 + i, 2 * n + 3 + i) for i in range(n)]
    border += [(0, n + 1), (0, 2 * n + 2), (n, 2 * n + 1), (n, 3 * n + 2)]
    edges = np.array(crease + border, dtype=np.int64)
    m_c, m_b = len(crease), len(border)
    pattern = CreasePattern(
        vertices=vertices,
        edges=edges,
        assignments=[_assignment(fold_angle_deg)] * m_c + ["B"] * m_b,
        fold_angles=[fold_angle_deg] * m_c + [np.nan] * m_b,
        edge_polyline=[0] * m_c + [1] * m_b,
        edge_from_curve=[True] * m_c + [False] * m_b,
        sources=["analytic parabola crease (bisector case)", "analytic border"],
    )
    bis = {(i, n + 1 + i) for i in range(1, n)} | {(i, 2 * n + 2 + i) for i in range(1, n)}
    return BisectorCase(pattern, bis, c, normals, float(width_left), float(width_right), n, float(fold_angle_deg))


# ---------------------------------------------------------------------------------------------------------------
# §3.2 continuous closed form: parabola crease, constant fold angle
# ---------------------------------------------------------------------------------------------------------------


def _hermite_chain(points: np.ndarray, tangents: np.ndarray) -> list[CurveSegment]:
    """Cubic Béziers through ``points`` with the given unit tangent directions (a C¹ approximation)."""
    segs = []
    for k in range(len(points) - 1):
        p0, p3 = points[k], points[k + 1]
        h = np.linalg.norm(p3 - p0) / 3.0
        segs.append(CurveSegment("cubic", np.array([p0, p0 + h * tangents[k], p3 - h * tangents[k + 1], p3])))
    return segs


@dataclass
class ParabolaStrip:
    """A parabola crease ``y = x²/(2p)`` for ``|x| ≤ half_width`` with its offset strip (ground-truth §3.2).

    ``curves``: the crease (one exact cubic Bézier, ``edge_from_curve`` after discretisation), the two offset borders
    (at distance ``width`` on both sides, C¹ cubic chains through exact offset points) and the two end normals
    (lines). ``interval``/``tolerance`` are the discretisation parameters to use (:meth:`pattern`).
    """

    p: float
    width: float
    half_width: float
    interval: float
    tolerance: float
    fold_angle_deg: float
    curves: list[CreaseCurve] = field(default_factory=list)

    def crease_point(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        return np.stack([x, x * x / (2.0 * self.p)], axis=-1)

    def pattern(self) -> CreasePattern:
        """The discretised pattern (needs ``core.pattern.discretize``, the INPUT helper's module)."""
        from curved_fold.core.pattern.discretize import discretize

        return discretize(self.curves, interval=self.interval, tolerance=self.tolerance)

    def flat_coordinates(self, flat_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(x_foot, w)``: the crease parameter of each point's normal foot and its signed distance (left > 0)."""
        f = np.asarray(flat_xy, dtype=float).reshape(-1, 2)
        x = f[:, 0].copy()
        p = self.p
        for _ in range(60):
            c = self.crease_point(x)
            dx, dy = f[:, 0] - c[:, 0], f[:, 1] - c[:, 1]
            g = dx + dy * x / p  # (F − c)·c'
            gp = -(1.0 + (x / p) ** 2) + dy / p
            step = g / gp
            x -= step
            if np.max(np.abs(step)) < 1e-14 * max(1.0, self.half_width):
                break
        c = self.crease_point(x)
        t = np.column_stack([np.ones_like(x), x / p]) / np.sqrt(1.0 + (x / p) ** 2)[:, None]
        n2 = np.column_stack([-t[:, 1], t[:, 0]])
        w = np.einsum("ij,ij->i", f - c, n2)
        return x, w

    def crease_3d(self, x: np.ndarray, rho_deg: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Folded crease ``X(x)`` (z = 0, apex fixed at the origin, apex tangent +x) and in-plane normal ``M``."""
        alpha = np.radians(self.fold_angle_deg if rho_deg is None else rho_deg) / 2.0
        x = np.asarray(x, dtype=float).reshape(-1)
        p = self.p
        # X(x) = ∫_0^x (cos φ3, sin φ3) √(1 + ξ²/p²) dξ with φ3 = atan(ξ/p) / cos α (apex tangent angle 0)
        xi = 0.5 * x[:, None] * (_GL_X[None, :] + 1.0)
        wts = 0.5 * x[:, None] * _GL_W[None, :]
        phi3 = np.arctan(xi / p) / np.cos(alpha)
        speed = np.sqrt(1.0 + (xi / p) ** 2)
        X = np.column_stack(
            [np.sum(wts * np.cos(phi3) * speed, 1), np.sum(wts * np.sin(phi3) * speed, 1), np.zeros(len(x))]
        )
        ph = np.arctan(x / p) / np.cos(alpha)
        M = np.column_stack([-np.sin(ph), np.cos(ph), np.zeros(len(x))])
        return X, M

    def exact_positions(self, flat_xy: np.ndarray, rho_deg: float | None = None) -> np.ndarray:
        """§3.2 closed form at flat points: ``P = X(s) + w cos α M(s) + |w| sin α e_z`` (shape ``(k, 3)``)."""
        alpha = np.radians(self.fold_angle_deg if rho_deg is None else rho_deg) / 2.0
        x, w = self.flat_coordinates(flat_xy)
        X, M = self.crease_3d(x, rho_deg)
        P = X + (w * np.cos(alpha))[:, None] * M
        P[:, 2] += np.abs(w) * np.sin(alpha)
        return P


def parabola_strip(
    p: float = 60.0,
    width: float = 20.0,
    interval: float = 7.0,
    tolerance: float = 0.07,
    fold_angle_deg: float = 108.0,
    *,
    half_width: float = 60.0,
    border_pieces: int = 8,
) -> ParabolaStrip:
    """The §3.2 parabola strip as curves (crease: exact cubic; borders: offset curves; ends: normal lines).

    Requires ``width / p < 1`` (the strip's normals must not cross: ``W·max|k| < 1``).
    """
    if not width < p:
        raise ValueError(f"parabola_strip: width {width} must be below the apex radius of curvature p = {p}")
    x0, x1 = -half_width, half_width
    q0 = np.array([x0, x0 * x0 / (2 * p)])
    q1 = np.array([0.5 * (x0 + x1), x0 * x1 / (2 * p)])
    q2 = np.array([x1, x1 * x1 / (2 * p)])
    cubic = np.array([q0, q0 + 2.0 / 3.0 * (q1 - q0), q2 + 2.0 / 3.0 * (q1 - q2), q2])
    strip = ParabolaStrip(p, width, half_width, interval, tolerance, fold_angle_deg)
    angle = float(fold_angle_deg)
    curves = [CreaseCurve([CurveSegment("cubic", cubic)], _assignment(angle), angle, source="parabola crease")]
    xs = np.linspace(x0, x1, border_pieces + 1)
    c = strip.crease_point(xs)
    t = np.column_stack([np.ones_like(xs), xs / p]) / np.sqrt(1.0 + (xs / p) ** 2)[:, None]
    n2 = np.column_stack([-t[:, 1], t[:, 0]])
    for sign, name in ((1.0, "left"), (-1.0, "right")):
        pts = c + sign * width * n2
        curves.append(CreaseCurve(_hermite_chain(pts, t), "B", None, source=f"{name} offset border"))
    for k, name in ((0, "start"), (-1, "end")):
        line = np.array([c[k] - width * n2[k], c[k], c[k] + width * n2[k]])
        segs = [CurveSegment("line", line[0:2]), CurveSegment("line", line[1:3])]
        curves.append(CreaseCurve(segs, "B", None, source=f"{name} normal border"))
    strip.curves = curves
    return strip


# ---------------------------------------------------------------------------------------------------------------
# §3.3 annular sector with one circular crease
# ---------------------------------------------------------------------------------------------------------------


@dataclass
class AnnularSector:
    """Annular sector ``r_in ≤ r ≤ r_out``, ``|θ| ≤ Θ/2``, circular crease at ``r = R`` (ground-truth §3.3)."""

    r_in: float
    R: float
    r_out: float
    theta_deg: float
    fold_angle_deg: float
    curves: list[CreaseCurve] = field(default_factory=list)

    def pattern(self, interval: float | None = None, tolerance: float | None = None) -> CreasePattern:
        """The discretised pattern (needs ``core.pattern.discretize``, the INPUT helper's module)."""
        from curved_fold.core.pattern.discretize import discretize

        return discretize(self.curves, interval=interval, tolerance=tolerance)

    def exact_positions(self, flat_xy: np.ndarray, rho_deg: float | None = None) -> np.ndarray:
        """Continuous closed form ``(r cos γ cos(θ/cos γ), r cos γ sin(θ/cos γ), |r − R| sin γ)``, ``γ = ρ/2``."""
        g = np.radians(self.fold_angle_deg if rho_deg is None else rho_deg) / 2.0
        f = np.asarray(flat_xy, dtype=float).reshape(-1, 2)
        r = np.hypot(f[:, 0], f[:, 1])
        th = np.arctan2(f[:, 1], f[:, 0]) / np.cos(g)
        return np.column_stack([r * np.cos(g) * np.cos(th), r * np.cos(g) * np.sin(th), np.abs(r - self.R) * np.sin(g)])

    def discrete_positions(self, flat_xy: np.ndarray, n: int, rho_deg: float | None = None) -> np.ndarray:
        """§3.3 discrete closed form for a crease polygon of ``n`` segments and radial mesh lines.

        ``flat_xy`` must lie on the radial lines through the crease polygon's vertices ``θ_j = −Θ/2 + jΔθ``.
        """
        g = np.radians(self.fold_angle_deg if rho_deg is None else rho_deg) / 2.0
        f = np.asarray(flat_xy, dtype=float).reshape(-1, 2)
        theta = np.radians(self.theta_deg)
        dth = theta / n
        r = np.hypot(f[:, 0], f[:, 1])
        j = np.rint((np.arctan2(f[:, 1], f[:, 0]) + theta / 2) / dth)
        rho_b = self.R * np.sqrt(np.sin(dth / 2) ** 2 + np.cos(dth / 2) ** 2 * np.cos(g) ** 2)
        dpsi = 2 * np.arctan(np.tan(dth / 2) / np.cos(g))
        psi = -n * dpsi / 2 + j * dpsi
        z = np.abs(self.R - r) * np.cos(dth / 2) * np.sin(g)
        return np.column_stack([r * rho_b / self.R * np.cos(psi), r * rho_b / self.R * np.sin(psi), z])


def annular_sector(
    r_in: float = 40.0,
    R: float = 70.0,
    r_out: float = 100.0,
    theta_deg: float = 90.0,
    fold_angle_deg: float = 108.0,
) -> AnnularSector:
    """The §3.3 sector as curves: crease arc at ``R``, border arcs at ``r_in``/``r_out``, radial border lines
    (each split at the crease end). Requires ``Θ / cos(ρ/2) ≤ 360°`` (no overlap when folded)."""
    g = np.radians(fold_angle_deg) / 2.0
    if np.radians(theta_deg) / np.cos(g) > 2 * np.pi + 1e-12:
        raise ValueError(f"annular_sector: Θ = {theta_deg}° overlaps itself at fold angle {fold_angle_deg}°")
    th = np.radians(theta_deg)
    a0 = -th / 2

    def arc(r: float) -> CurveSegment:
        ends = np.array([[r * np.cos(a0), r * np.sin(a0)], [r * np.cos(-a0), r * np.sin(-a0)]])
        return CurveSegment("arc", ends, arc=(0.0, 0.0, r, r, 0.0, a0, th))

    angle = float(fold_angle_deg)
    curves = [
        CreaseCurve([arc(R)], _assignment(angle), angle, source="circular crease"),
        CreaseCurve([arc(r_in)], "B", None, source="inner border arc"),
        CreaseCurve([arc(r_out)], "B", None, source="outer border arc"),
    ]
    for a, name in ((a0, "lower"), (-a0, "upper")):
        u = np.array([np.cos(a), np.sin(a)])
        segs = [CurveSegment("line", np.array([r_in * u, R * u])), CurveSegment("line", np.array([R * u, r_out * u]))]
        curves.append(CreaseCurve(segs, "B", None, source=f"{name} radial border"))
    return AnnularSector(r_in, R, r_out, theta_deg, angle, curves)
