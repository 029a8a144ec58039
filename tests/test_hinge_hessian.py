"""The closed-form hinge curvature ∇²θ (``forces.hinge_angle_hessian``) is the Jacobian of the hinge gradient: it
equals the complex-step Jacobian of :func:`hinge_angle_gradient` (here: the engine's formula written with analytic
operations only; exact to round-off) on random hinges and on nearly flat and nearly closed ones, valley and mountain
side; degenerate hinges give zeros, not inf/nan. The face blocks (closed-form ∇²α) equal the complex-step Jacobian of
:func:`corner_angle_gradient` likewise."""

from __future__ import annotations

import numpy as np
import pytest

from curved_fold.core.solve import forces as F  # noqa: N812
from curved_fold.core.solve.model import build_model
from curved_fold.core.solve.newton import HessianAssembler
from tests.test_forces import grid_mesh

COMPLEX_STEP = 1e-30
"""Imaginary step of the complex-step differentiation of the element gradients (exact to round-off)."""


def _csqrt_unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``v / |v|`` and ``|v|`` written with analytic operations only (valid for complex-step arguments)."""
    norm = np.sqrt(np.einsum("...k,...k->...", v, v))
    return v / norm[..., None], norm


def hinge_angle_gradient(x1: np.ndarray, x2: np.ndarray, x3: np.ndarray, x4: np.ndarray) -> np.ndarray:
    """``∇θ`` ``(m, 4, 3)`` with respect to wing 1, wing 2, edge node 1, edge node 2 (reference §3.4).

    The same formula as ``forces.evaluate`` (``n/h`` on the wings, foot fractions ``t`` on the edge nodes), written
    with analytic operations only so that complex-step differentiation gives its exact Jacobian ``∇²θ``: the
    reference the closed form (``forces.hinge_angle_hessian``) is tested against.
    """
    e = x4 - x3
    chat, L = _csqrt_unit(e)
    r1, r2 = x1 - x3, x2 - x3
    n1 = _csqrt_unit(F._cross(e, r1))[0]  # (v2 − v1) × (w1 − v1): the normal of the face left of v1 → v2
    n2 = _csqrt_unit(F._cross(x3 - x4, x2 - x4))[0]
    p1, p2 = F._rows_dot(chat, r1), F._rows_dot(chat, r2)
    h1 = np.sqrt(F._rows_dot(r1, r1) - p1 * p1)
    h2 = np.sqrt(F._rows_dot(r2, r2) - p2 * p2)
    t1, t2 = p1 / L, p2 / L
    g1 = n1 / h1[:, None]
    g2 = n2 / h2[:, None]
    g3 = -((1.0 - t1)[:, None] * g1 + (1.0 - t2)[:, None] * g2)
    g4 = -(t1[:, None] * g1 + t2[:, None] * g2)
    return np.stack([g1, g2, g3, g4], axis=1)


def corner_angle_gradient(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """``∂α_corner/∂x_node`` ``(m, 3, 3, 3)`` of the three corner angles of triangles ``(a, b, c)`` (reference §3.5),
    with analytic operations only (for complex-step differentiation: the tests' reference for the face blocks)."""
    e_ab, l_ab = _csqrt_unit(b - a)
    e_ac, l_ac = _csqrt_unit(c - a)
    e_bc, l_bc = _csqrt_unit(c - b)
    nrm = _csqrt_unit(F._cross(b - a, c - a))[0]
    P_ab = F._cross(nrm, e_ab) / l_ab[:, None]
    P_ac = F._cross(nrm, e_ac) / l_ac[:, None]
    P_bc = F._cross(nrm, e_bc) / l_bc[:, None]
    return np.stack(
        [
            np.stack([P_ab - P_ac, -P_ab, P_ac], axis=1),
            np.stack([-P_ab, P_ab + P_bc, -P_bc], axis=1),
            np.stack([P_ac, -P_bc, P_bc - P_ac], axis=1),
        ],
        axis=1,
    )


def _complex_step_jacobian(function, points: np.ndarray) -> np.ndarray:
    """Jacobian of a vectorised gradient ``function(*nodes) -> (m, …, 3)`` by complex steps, all at once.

    ``points`` is ``(m, q, 3)`` (q nodes per element); returns ``(m, …, q, 3)``: the derivative of every output
    entry by every node coordinate, exact to round-off (no subtraction, so no step-size error).
    """
    m, q, _ = points.shape
    z = np.broadcast_to(points, (3 * q, m, q, 3)).astype(np.complex128)
    for k in range(3 * q):
        z[k, :, k // 3, k % 3] += 1j * COMPLEX_STEP
    z = z.reshape(3 * q * m, q, 3)
    out = function(*(z[:, node] for node in range(q))).imag / COMPLEX_STEP  # (3q·m, …)
    out = out.reshape(3 * q, m, *out.shape[1:])
    return np.moveaxis(out, 0, -1).reshape(m, *out.shape[2:], q, 3)


def complex_step_hessian(points: np.ndarray) -> np.ndarray:
    """Reference ∇²θ ``(m, 4, 4, 3, 3)`` rows ``[a, b, i, j]``: complex-step Jacobian of the analytic gradient."""
    return _complex_step_jacobian(hinge_angle_gradient, points).transpose(0, 1, 3, 2, 4)


def closed_form(points: np.ndarray, weight: np.ndarray | None = None) -> np.ndarray:
    return F.hinge_angle_hessian(points[:, 0], points[:, 1], points[:, 2], points[:, 3], weight)


def relative_error(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per hinge: max |a − b| over max |b|."""
    axes = tuple(range(1, a.ndim))
    return np.max(np.abs(a - b), axis=axes) / np.max(np.abs(b), axis=axes)


def hinges_at(theta: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Hinges ``(m, 4, 3)`` (wing 1, wing 2, edge node 1, edge node 2) with fold angle ``theta`` (rad, valley > 0),
    random edge length, moment arms, foot fractions (also outside [0, 1]), then rotated and moved at random."""
    m = len(theta)
    L = rng.uniform(0.3, 2.0, m)
    h1, h2 = rng.uniform(0.1, 1.5, m), rng.uniform(0.1, 1.5, m)
    t1, t2 = rng.uniform(-0.4, 1.4, m), rng.uniform(-0.4, 1.4, m)
    out = np.zeros((m, 4, 3))
    out[:, 3, 0] = L  # edge along x; face 1 (v1, v2, w1) counter-clockwise seen from +z: normal +z
    out[:, 0, 0], out[:, 0, 1] = t1 * L, h1
    # wing 2 on the other side (−y when flat), turned about the edge: raising both wings toward +z is a valley
    phi = np.pi - theta
    out[:, 1, 0] = t2 * L
    out[:, 1, 1] = h2 * np.cos(phi)
    out[:, 1, 2] = h2 * np.sin(phi)
    q, _ = np.linalg.qr(rng.normal(size=(m, 3, 3)))
    return np.einsum("mij,mnj->mni", q, out) + rng.normal(size=(m, 1, 3))


def test_setup_has_the_intended_fold_angle_and_sign():
    theta = np.array([0.5, -0.5, 3.0, -3.0, 1e-7, -1e-7])
    np.testing.assert_allclose(fold_angle(hinges_at(theta, np.random.default_rng(0))), theta, atol=1e-9)


def test_closed_form_equals_complex_step_on_random_hinges():
    rng = np.random.default_rng(1)
    p = rng.normal(size=(400, 4, 3))
    ref = complex_step_hessian(p)
    H = closed_form(p)
    assert np.max(relative_error(H, ref)) < 1e-10
    assert np.max(np.abs(ref)) > 1.0  # a real comparison, not of zeros


@pytest.mark.parametrize(
    "theta",
    [
        pytest.param(np.array([1e-9, -1e-9, 1e-5, -1e-5, 0.0]), id="nearly-flat"),
        pytest.param(np.array([np.pi - 1e-9, -(np.pi - 1e-9), np.pi - 1e-5, -(np.pi - 1e-5), 3.1]), id="nearly-closed"),
        pytest.param(np.linspace(-3.1, 3.1, 63), id="valley-and-mountain"),
    ],
)
def test_closed_form_equals_complex_step_flat_and_closed(theta):
    rng = np.random.default_rng(2)
    p = hinges_at(np.repeat(theta, 8), rng)
    ref = complex_step_hessian(p)
    H = closed_form(p)
    assert np.max(relative_error(H, ref)) < 1e-10


def fold_angle(p: np.ndarray) -> np.ndarray:
    """θ of hinges ``(m, 4, 3)`` by the formula of ``evaluate`` (atan2, valley > 0)."""
    x1, x2, x3, x4 = (p[:, q] for q in range(4))
    n1 = F._unit(F._cross(x4 - x3, x1 - x3))[0]
    n2 = F._unit(F._cross(x3 - x4, x2 - x4))[0]
    chat = F._unit(x4 - x3)[0]
    return np.arctan2(F._rows_dot(F._cross(n1, chat), n2), np.clip(F._rows_dot(n1, n2), -1, 1))


def test_curvature_is_the_second_derivative_of_the_angle_on_both_sides():
    """vᵀ∇²θv equals d²θ/ds² along x + s v (central differences of θ itself), for valleys and mountains alike:
    the sign convention of ∇²θ is that of θ, independently of the gradient formula."""
    rng = np.random.default_rng(6)
    theta = np.repeat([0.5, -0.5, 2.0, -2.0, 3.0, -3.0], 10)
    p = hinges_at(theta, rng)
    v = rng.normal(size=p.shape)
    s = 1e-4
    fd = (fold_angle(p + s * v) - 2.0 * fold_angle(p) + fold_angle(p - s * v)) / (s * s)
    quad = np.einsum("mai,mabij,mbj->m", v, closed_form(p), v)
    np.testing.assert_allclose(fold_angle(p), theta, atol=1e-9)
    assert np.max(np.abs(quad - fd)) < 1e-5 * np.max(np.abs(quad))
    assert np.min(np.abs(quad)) > 1e-3  # real curvature, not zeros
    # mirroring a hinge flips θ and its curvature; the closed form follows
    mirror = np.diag([1.0, 1.0, -1.0])
    pm = p @ mirror
    np.testing.assert_allclose(fold_angle(pm), -fold_angle(p), atol=1e-12)
    Hm = np.einsum("ik,mabkl,lj->mabij", mirror, closed_form(pm), mirror)
    assert np.max(np.abs(Hm + closed_form(p))) < 1e-10 * np.max(np.abs(closed_form(p)))


def test_weight_and_symmetry():
    rng = np.random.default_rng(3)
    p = rng.normal(size=(50, 4, 3))
    w = rng.normal(size=50)
    H = closed_form(p, w)
    np.testing.assert_allclose(H, w[:, None, None, None, None] * closed_form(p), rtol=0, atol=1e-12 * np.max(np.abs(H)))
    # ∇²θ is symmetric ([a, b, i, j] = [b, a, j, i]) and translation-invariant (rows sum to zero over the nodes)
    sym = H.transpose(0, 2, 1, 4, 3)
    assert np.max(np.abs(H - sym)) < 1e-10 * np.max(np.abs(H))
    assert np.max(np.abs(H.sum(axis=2))) < 1e-10 * np.max(np.abs(H))


def test_degenerate_hinges_are_zero_not_nan():
    rng = np.random.default_rng(4)
    p = rng.normal(size=(4, 4, 3))
    p[0, 3] = p[0, 2]  # edge of zero length
    p[1, 0] = p[1, 2] + 0.3 * (p[1, 3] - p[1, 2])  # wing 1 on the crease line: moment arm 0
    p[2, 1] = p[2, 3]  # wing 2 on an edge node
    H = closed_form(p, np.ones(4))
    assert np.all(np.isfinite(H))
    assert np.all(H[:3] == 0.0)
    assert np.max(relative_error(H[3:], complex_step_hessian(p[3:]))) < 1e-10


def test_exact_hessian_blocks_use_the_closed_form():
    """The hinge blocks of ``exact_hessian_blocks`` are k∇θ∇θᵀ + k(θ − θ̄)∇²θ with the complex-step ∇²θ."""
    mesh = grid_mesh(3, 3, creases={(1, 5): ("V", 90.0), (5, 9): ("M", -60.0), (2, 6): ("U", np.nan)})
    model = build_model(mesh)
    x = model.rest + np.random.default_rng(5).normal(0, 0.08, model.rest.shape)
    theta = F.fold_angles(model, x)
    ev = F.evaluate(model, x, theta, 0.7, jacobians=True)
    _, hinges, _ = F.exact_hessian_blocks(model, x, ev)
    g, k = ev.hinge_grad, ev.hinge_k
    nodes = np.column_stack([model.hinge_wings, model.hinge_edge_nodes])
    ref = k[:, None, None, None, None] * g[:, :, None, :, None] * g[:, None, :, None, :]
    ref += (k * ev.hinge_dev)[:, None, None, None, None] * complex_step_hessian(x[nodes])
    assert np.max(np.abs(hinges - ref)) < 1e-12 * np.max(np.abs(ref))
    # and the assembler scatters the same matrix as the plain [a, b, i, j] blocks would
    assembler = HessianAssembler(model)
    bars, _, faces = F.exact_hessian_blocks(model, x, ev)
    plain = assembler.matrix.assemble(
        np.concatenate(
            [assembler.bar_index.reshape(-1), assembler.hinge_index.reshape(-1), assembler.face_index.reshape(-1)]
        ),
        np.concatenate(
            [
                np.concatenate([bars, bars, -bars, -bars]).reshape(-1),
                np.ascontiguousarray(ref).reshape(-1),
                faces.reshape(-1),
            ]
        ),
    )
    H = assembler.assemble_exact(x, ev)
    assert np.max(np.abs(H[:-1] - plain[:-1])) < 1e-12 * np.max(np.abs(plain))


@pytest.mark.parametrize("seed", [0, 1])
def test_face_blocks_equal_the_complex_step_curvature(seed):
    """The face blocks Σ φ''∇α∇αᵀ + φ'∇²α (closed form through the edge lengths) equal the same sum with ∇²α
    the complex-step Jacobian of ``corner_angle_gradient``; also with squashed and stretched corners."""
    mesh = grid_mesh(3, 3, creases={(1, 5): ("V", 90.0), (5, 9): ("M", -60.0)})
    model = build_model(mesh, face_stiffness=0.3)
    rng = np.random.default_rng(seed)
    x = model.rest + rng.normal(0, 0.08, model.rest.shape)
    x[5] = 0.5 * (x[4] + x[6]) + 1e-4 * rng.normal(size=3)  # two corners near 180°, one near 0°
    ev = F.evaluate(model, x, F.fold_angles(model, x), 0.7, jacobians=True)
    _, _, faces = F.exact_hessian_blocks(model, x, ev)
    tri = model.triangles
    d2 = _complex_step_jacobian(corner_angle_gradient, x[tri])  # (t, corner, a, i, b, j)
    ref = np.einsum("tc,tcai,tcbj->tabij", ev.face_ddphi, ev.face_grad, ev.face_grad)
    ref += np.einsum("tc,tcaibj->tabij", ev.face_dphi, d2)
    assert np.max(np.abs(ref)) > 1.0
    assert np.max(np.abs(faces - ref)) < 1e-10 * np.max(np.abs(ref))


def flat_wing_model():
    """Two crease hinges; the first has one wing (node 2) 0.02 from its hinge line: a flat triangle (178.9° at
    node 2), whose hinge stiffness fades (``forces.flat_attenuation``)."""
    from curved_fold.core.solve.model import mesh_from_triangles

    vertices = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 0.02], [1.0, -1.0], [3.0, -0.5]])
    triangles = np.array([[0, 1, 2], [1, 0, 3], [1, 3, 4]])
    return build_model(mesh_from_triangles(vertices, triangles, {(0, 1): ("V", 90.0), (1, 3): ("M", -60.0)}))


def test_fading_hinge_forces_and_exact_hessian_are_the_derivatives_of_its_energy():
    """A wing of a flat triangle squashed to 30 % of its rest moment arm: the hinge's stiffness is fading
    (``k₀ att(h1, h2)``), the forces are −∇E and the exact Hessian (with the terms of ``att``'s derivatives) is
    −∂F/∂x, by central differences. At rest it is Origami Simulator's hinge."""
    from tests.test_solver_tail import dense, finite_difference_hessian

    model = flat_wing_model()
    at_rest = F.evaluate(model, model.rest, np.zeros(2), 0.8, jacobians=True)
    assert len(at_rest.hinge_fading) == 0 and np.array_equal(at_rest.hinge_k, model.hinge_k)
    x = model.rest.copy()
    x[3, 2] += 0.3
    x[4, 2] -= 0.1
    foot = 0.5 * (x[0] + x[1])
    x[2] = foot + 0.3 * (x[2] - foot)
    x += np.random.default_rng(0).normal(0, 1e-5, x.shape)
    theta = F.fold_angles(model, x)
    ev = F.evaluate(model, x, theta, 0.8, jacobians=True)
    assert list(ev.hinge_fading) == [0] and 0.1 < ev.hinge_k[0] / model.hinge_k[0] < 0.99
    eps = 1e-7
    grad = np.zeros(x.size)
    for k in range(x.size):
        step = np.zeros(x.size)
        step[k] = eps
        up = F.evaluate(model, x + step.reshape(x.shape), theta, 0.8, forces=False).energy
        down = F.evaluate(model, x - step.reshape(x.shape), theta, 0.8, forces=False).energy
        grad[k] = (up - down) / (2 * eps)
    np.testing.assert_allclose(ev.forces.reshape(-1), -grad, atol=1e-7 * np.max(np.abs(grad)))
    assembler = HessianAssembler(model)
    H = dense(assembler, assembler.assemble_exact(x, ev))
    fd = finite_difference_hessian(model, x, theta, 0.8)
    assert np.max(np.abs(H - fd)) < 1e-6 * np.max(np.abs(H))


def test_hinge_energy_is_continuous_when_a_flat_triangle_turns_inside_out():
    """The wing of a flat triangle crossing its hinge line flips the fold angle by 180°: without the fading the
    energy jumped there (the solver stalled on it: tangent creases, a curve crossing straight pleats); with it the
    energy on both sides of the line tends to the same value and the force stays bounded."""
    from dataclasses import replace

    model = flat_wing_model()
    x = model.rest.copy()
    x[3, 2] += 0.3
    theta = F.fold_angles(model, x)
    foot = 0.5 * (model.rest[0] + model.rest[1])

    def across(m, h):
        out = []
        for side in (1.0, -1.0):
            y = x.copy()
            y[2] = foot + np.array([0.0, side * h, 0.0])
            out.append(F.evaluate(m, y, theta, 0.8))
        return out

    for h in (1e-5, 1e-7):
        above, below = across(model, h)
        assert abs(above.energy - below.energy) < 1e3 * h  # → 0 with h
        assert np.max(np.abs(above.forces)) < 1e3 and np.max(np.abs(below.forces)) < 1e3
    above, below = across(replace(model, hinge_flat_scale=None), 1e-5)  # Origami Simulator's hinge: a jump
    assert abs(above.energy - below.energy) > 1.0


def test_fading_is_c2_force_and_hessian_vanish_at_the_hinge_line():
    """``σ = 10u³ − 15u⁴ + 6u⁵`` from ``FLAT_DEAD`` of the fading scale (fifth pass): as the wing of a flat triangle
    comes down to it, the hinge's force on the wing falls as (h − h₀)² and its Hessian as (h − h₀); below it the
    hinge has no stiffness at all (a triangle pressed flat has no dihedral angle). With the C¹ fading
    (``3u² − 2u³``) the force fell only linearly and the Hessian stayed ~k₀/s², so Newton's model held only within ~h
    of a squashed triangle and the fuzz run's folds that pressed one flat stalled (9 of 1,400); with the C² fading
    down to the line itself, the last stiffness turned the flat triangle about the line 0.25° per iteration (3 folds
    at the iteration budget)."""
    from dataclasses import replace

    from curved_fold.core.solve.model import FLAT_DEAD
    from tests.test_solver_tail import dense

    model = replace(flat_wing_model(), face_k=0.0)
    model = replace(model, bar_k=model.bar_k * 0.0)  # the hinges alone: node 2 is a wing of hinge 0 only
    w = int(np.flatnonzero(model.hinge_wings[0] == 2)[0])
    s = float(model.hinge_flat_scale[0, w])
    x = model.rest.copy()
    x[3, 2] += 0.3
    theta = F.fold_angles(model, x)
    foot = 0.5 * (model.rest[0] + model.rest[1])
    assembler = HessianAssembler(model)

    def at(h):
        y = x.copy()
        y[2] = foot + np.array([0.0, h, 0.0])
        ev = F.evaluate(model, y, theta, 0.8, jacobians=True)
        assert list(ev.hinge_fading) == ([0] if h > h0 else [])  # below h₀ the hinge is off, not fading
        H = dense(assembler, assembler.assemble_exact(y, ev))
        return np.linalg.norm(ev.forces[2]), np.max(np.abs(H[6:9, 6:9])), ev.hinge_k[0]

    h0 = FLAT_DEAD * s
    (f1, b1, _), (f2, b2, _) = (at(h0 + v * (s - h0)) for v in (1e-2, 1e-4))
    assert f2 < 1e-3 * f1  # ~(h − h₀)²: 1e-4 (C¹: 1e-2)
    assert b2 < 0.1 * b1  # ~(h − h₀): 1e-2 (C¹: ~1)
    force, block, k = at(0.5 * h0)
    assert k == 0.0 and force == 0.0 and block == 0.0
