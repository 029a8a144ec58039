"""Energy, forces and Gauss–Newton Hessian blocks of the bar-and-hinge model (reference §3.3–3.5), vectorised.

One energy is shared by every solver::

    E = Σ_bars ½ k (ℓ − L0)²  +  Σ_hinges ½ k (θ − p θ̄)²  +  Σ_triangles ½ k_f Σ_corners (α − α0)²

The forces returned are its exact negative gradient (checked by finite differences in ``tests/test_forces.py``);
they are Origami Simulator's formulas: the 4-node hinge forces with moment arms ``h`` and foot fractions ``t``
recomputed from the current positions, the in-plane face-angle forces, and the axial bar forces. The fold angle θ
is unwrapped against the previous θ with Origami Simulator's ±5 rad rule so it can pass ±π continuously.
Degenerate hinges (edge or moment arm < 1e-6) and degenerate triangles (a side < 1e-7) are skipped for the
evaluation, as in Origami Simulator.

Per-node sums use ``np.bincount`` on flattened ``node*3 + component`` indices (one call per evaluation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model import BarHingeModel

HINGE_EPS = 1e-6
FACE_EPS = 1e-7

FACE_SMOOTH = np.radians(1.0)
"""Width (rad) of the smooth cap of the face-angle energy at 0° and 180° (see :func:`face_angle_energy`)."""

COMPLEX_STEP = 1e-30
"""Imaginary step of the complex-step differentiation of the element gradients (exact to round-off)."""


@dataclass
class Evaluation:
    """One evaluation of the model at positions ``x`` (normalised units).

    ``theta`` is the unwrapped fold angle per hinge (rad). ``forces`` is ``-∇E`` (``(n, 3)``), present when
    requested. The ``*_grad``/``*_k`` arrays are the per-element Jacobians the Gauss–Newton Hessian is built from.
    """

    energy: float
    theta: np.ndarray
    forces: np.ndarray | None = None
    bar_blocks: np.ndarray | None = None
    hinge_grad: np.ndarray | None = None
    hinge_k: np.ndarray | None = None
    face_grad: np.ndarray | None = None
    hinge_dev: np.ndarray | None = None
    face_dphi: np.ndarray | None = None
    face_ddphi: np.ndarray | None = None


def _rows_dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", u, v)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of ``(m, 3)`` arrays (``np.cross`` spends most of its time on axis bookkeeping)."""
    out = np.empty_like(a)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def _unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    norm = np.sqrt(np.einsum("...k,...k->...", v, v))
    safe = np.where(norm > 0, norm, 1.0)
    return v / safe[..., None], norm


def triangle_normals(x: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unit normals ``(b − a) × (c − a)`` of the triangles in stored (counter-clockwise) order."""
    a, b, c = (x[triangles[:, k]] for k in range(3))
    return _unit(_cross(b - a, c - a))[0]


def unwrap(theta_raw: np.ndarray, theta_prev: np.ndarray) -> np.ndarray:
    """Origami Simulator's unwrapping: jumps of more than 5 rad against the previous θ are taken as ±2π."""
    delta = theta_raw - theta_prev
    delta = np.where(delta < -5.0, delta + 2.0 * np.pi, delta)
    delta = np.where(delta > 5.0, delta - 2.0 * np.pi, delta)
    return theta_prev + delta


def fold_angles(model: BarHingeModel, x: np.ndarray, theta_prev: np.ndarray | None = None) -> np.ndarray:
    """Unwrapped fold angle θ (rad) of every hinge at positions ``x`` (valley > 0)."""
    return evaluate(model, x, theta_prev, 0.0, forces=False).theta


def evaluate(
    model: BarHingeModel,
    x: np.ndarray,
    theta_prev: np.ndarray | None,
    percent: float,
    *,
    forces: bool = True,
    jacobians: bool = False,
    damping_velocity: np.ndarray | None = None,
) -> Evaluation:
    """Energy (and forces, and optionally the element Jacobians) at positions ``x`` for fold percent ``percent``.

    ``theta_prev`` (rad, per hinge) is the previous fold angle used for unwrapping; ``None`` means zeros, as in
    Origami Simulator's reset state. ``damping_velocity`` (``(n, 3)``) adds the bar damping ``c (v_j − v_i)`` to the
    returned forces in the same scatter (the faithful integrator's step); it does not change the energy.
    """
    n = model.n_nodes
    if theta_prev is None:
        theta_prev = np.zeros(len(model.hinge_k))
    idx_parts: list[np.ndarray] = []
    val_parts: list[np.ndarray] = []
    out = Evaluation(energy=0.0, theta=theta_prev)

    # --- axial bars -------------------------------------------------------------------------------------------
    i, j = model.bar_nodes[:, 0], model.bar_nodes[:, 1]
    d = x[j] - x[i]
    dhat, ell = _unit(d)
    stretch = ell - model.bar_length
    energy = 0.5 * float(np.dot(model.bar_k, stretch * stretch))
    if forces:
        f = (model.bar_k * stretch)[:, None] * dhat  # force on i (towards j when stretched)
        if damping_velocity is not None:
            f = f + model.bar_c[:, None] * (damping_velocity[j] - damping_velocity[i])
        idx_parts += [i, j]
        val_parts += [f, -f]
    if jacobians:
        # PSD part of the bar Hessian: k (d̂d̂ᵀ + max(0, 1 − L0/ℓ)(I − d̂d̂ᵀ)); the geometric term is dropped in
        # compression, where it would be negative.
        geo = np.maximum(0.0, 1.0 - model.bar_length / np.where(ell > 0, ell, 1.0))
        outer = dhat[:, :, None] * dhat[:, None, :]
        out.bar_blocks = model.bar_k[:, None, None] * (outer + geo[:, None, None] * (np.eye(3) - outer))

    # --- hinges -----------------------------------------------------------------------------------------------
    normals = None
    if len(model.hinge_k):
        v1, v2 = model.hinge_edge_nodes[:, 0], model.hinge_edge_nodes[:, 1]
        w1, w2 = model.hinge_wings[:, 0], model.hinge_wings[:, 1]
        x3, x4, x1, x2 = x[v1], x[v2], x[w1], x[w2]
        normals = triangle_normals(x, model.triangles)
        n1, n2 = normals[model.hinge_faces[:, 0]], normals[model.hinge_faces[:, 1]]
        chat, L = _unit(x4 - x3)
        raw = np.arctan2(_rows_dot(_cross(n1, chat), n2), np.clip(_rows_dot(n1, n2), -1.0, 1.0))
        theta = unwrap(raw, theta_prev)
        r1, r2 = x1 - x3, x2 - x3
        p1, p2 = _rows_dot(chat, r1), _rows_dot(chat, r2)
        h1 = np.sqrt(np.abs(_rows_dot(r1, r1) - p1 * p1))
        h2 = np.sqrt(np.abs(_rows_dot(r2, r2) - p2 * p2))
        ok = (L >= HINGE_EPS) & (h1 >= HINGE_EPS) & (h2 >= HINGE_EPS)
        theta = np.where(ok, theta, theta_prev)
        out.theta = theta
        k = np.where(ok, model.hinge_k, 0.0)
        dev = theta - model.hinge_target * float(percent)
        energy += 0.5 * float(np.dot(k, dev * dev))
        if forces or jacobians:
            Ls = np.where(ok, L, 1.0)
            t1, t2 = p1 / Ls, p2 / Ls
            g1 = n1 / np.where(ok, h1, 1.0)[:, None]
            g2 = n2 / np.where(ok, h2, 1.0)[:, None]
            g3 = -((1.0 - t1)[:, None] * g1 + (1.0 - t2)[:, None] * g2)
            g4 = -(t1[:, None] * g1 + t2[:, None] * g2)
            if forces:
                tau = (-k * dev)[:, None]
                idx_parts += [w1, w2, v1, v2]
                val_parts += [tau * g1, tau * g2, tau * g3, tau * g4]
            if jacobians:
                out.hinge_grad = np.stack([g1, g2, g3, g4], axis=1)
                out.hinge_k = k
                out.hinge_dev = dev

    # --- face-angle springs -----------------------------------------------------------------------------------
    if model.face_k > 0:
        tri = model.triangles
        a, b, c = x[tri[:, 0]], x[tri[:, 1]], x[tri[:, 2]]
        e_ab, l_ab = _unit(b - a)
        e_ac, l_ac = _unit(c - a)
        e_bc, l_bc = _unit(c - b)
        ok = (l_ab >= FACE_EPS) & (l_ac >= FACE_EPS) & (l_bc >= FACE_EPS)
        alpha = np.stack(
            [
                np.arccos(np.clip(_rows_dot(e_ab, e_ac), -1, 1)),
                np.arccos(np.clip(-_rows_dot(e_ab, e_bc), -1, 1)),
                np.arccos(np.clip(_rows_dot(e_ac, e_bc), -1, 1)),
            ],
            axis=1,
        )
        phi, dphi, ddphi = face_angle_energy(alpha, model.face_alpha0, model.face_k)
        energy += float(np.sum(phi[ok]))
        # dev · k_f is the energy's slope dφ/dα (= k_f (α − α0) away from the caps)
        dev = np.where(ok[:, None], dphi / model.face_k, 0.0)
        if forces or jacobians:
            nrm = normals if normals is not None else triangle_normals(x, tri)
            P_ab = _cross(nrm, e_ab) / np.where(ok, l_ab, 1.0)[:, None]
            P_ac = _cross(nrm, e_ac) / np.where(ok, l_ac, 1.0)[:, None]
            P_bc = _cross(nrm, e_bc) / np.where(ok, l_bc, 1.0)[:, None]
            if forces and not jacobians:
                # the same negative gradient, written out per node (reference §3.5) without the 4-D Jacobian
                ka, kb, kc = (np.where(ok, -model.face_k * dev[:, q], 0.0)[:, None] for q in range(3))
                idx_parts += [tri[:, 0], tri[:, 1], tri[:, 2]]
                val_parts += [
                    ka * (P_ab - P_ac) - kb * P_ab + kc * P_ac,
                    -ka * P_ab + kb * (P_ab + P_bc) - kc * P_bc,
                    ka * P_ac - kb * P_bc + kc * (P_bc - P_ac),
                ]
            if jacobians:
                # grad[t, corner, node] = ∂α_corner / ∂x_node (nodes a, b, c)
                grad = np.stack(
                    [
                        np.stack([P_ab - P_ac, -P_ab, P_ac], axis=1),
                        np.stack([-P_ab, P_ab + P_bc, -P_bc], axis=1),
                        np.stack([P_ac, -P_bc, P_bc - P_ac], axis=1),
                    ],
                    axis=1,
                )
                grad = np.where(ok[:, None, None, None], grad, 0.0)
                if forces:
                    f = -model.face_k * np.einsum("tc,tcnk->tnk", dev, grad)
                    idx_parts += [tri[:, 0], tri[:, 1], tri[:, 2]]
                    val_parts += [f[:, 0], f[:, 1], f[:, 2]]
                out.face_grad = grad
                out.face_dphi = np.where(ok[:, None], dphi, 0.0)
                out.face_ddphi = np.where(ok[:, None], ddphi, 0.0)

    out.energy = energy
    if forces:
        out.forces = scatter(n, idx_parts, val_parts)
    return out


def scatter(n: int, nodes: list[np.ndarray], values: list[np.ndarray]) -> np.ndarray:
    """Sum per-element 3-vectors ``values[k][m]`` into nodes ``nodes[k][m]``: one ``bincount`` for all of them."""
    idx = np.concatenate(nodes)
    vals = np.concatenate(values)
    flat = (idx[:, None] * 3 + np.arange(3)).reshape(-1)
    return np.bincount(flat, weights=vals.reshape(-1), minlength=3 * n).reshape(n, 3)


def damping_forces(model: BarHingeModel, v: np.ndarray) -> np.ndarray:
    """Origami Simulator's bar damping ``c (v_j − v_i)`` on node i (full relative velocity, reference §3.3)."""
    i, j = model.bar_nodes[:, 0], model.bar_nodes[:, 1]
    f = model.bar_c[:, None] * (v[j] - v[i])
    return scatter(model.n_nodes, [i, j], [f, -f])


def characteristic_force(model: BarHingeModel, crease_stiffness: float, panel_stiffness: float) -> float:
    """Force scale used to make residuals dimensionless: a hinge stiffness per unit length × 1 rad.

    In the normalised model a hinge of length L and moment arm h ≈ L exerts about ``k_per_length · Δθ`` on its
    wings, so this is the force of a hinge one radian off its target — independent of the pattern's units and size.
    """
    scale = max(crease_stiffness, panel_stiffness)
    return float(scale) if scale > 0 else 1.0


def hessian_matvec(model: BarHingeModel, ev: Evaluation, v: np.ndarray) -> np.ndarray:
    """Gauss–Newton Hessian (the PSD blocks of ``ev``, see ``core.solve.newton``) times ``v`` (``(n, 3)``).

    Element by element, without assembling a matrix: bars ``K_b (v_j − v_i)``, hinges ``k ∇θ (∇θ·v)``, faces
    ``k_f Σ ∇α (∇α·v)``. Used by the power iteration of the time-step bound and by preconditioned CG.
    """
    n = model.n_nodes
    i, j = model.bar_nodes[:, 0], model.bar_nodes[:, 1]
    fb = np.einsum("bij,bj->bi", ev.bar_blocks, v[j] - v[i])
    nodes, vals = [i, j], [-fb, fb]
    if ev.hinge_grad is not None and len(ev.hinge_k):
        g = ev.hinge_grad
        hn = np.column_stack([model.hinge_wings, model.hinge_edge_nodes])
        s = ev.hinge_k * np.einsum("hak,hak->h", g, v[hn])
        nodes += [hn[:, q] for q in range(4)]
        vals += [s[:, None] * g[:, q] for q in range(4)]
    if ev.face_grad is not None:
        fg = ev.face_grad
        tri = model.triangles
        c = model.face_k * np.einsum("tcak,tak->tc", fg, v[tri])
        nodes += [tri[:, q] for q in range(3)]
        vals += [np.einsum("tc,tck->tk", c, fg[:, :, q]) for q in range(3)]
    return scatter(n, nodes, vals)


def damping_matvec(model: BarHingeModel, v: np.ndarray) -> np.ndarray:
    """Damping matrix times ``v``: ``C v = −damping_forces(v)`` (a weighted graph Laplacian, PSD)."""
    return -damping_forces(model, v)


def face_angle_energy(alpha: np.ndarray, alpha0: np.ndarray, k: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Energy ``φ(α)`` of every face corner and its first two derivatives in α (arrays shaped like ``alpha``).

    ``φ = ½ k (α − α0)²`` (Origami Simulator's face-angle spring) except within ``δ`` of 0° and of 180°, where it is
    the parabola in ``α²`` (resp. ``(π − α)²``) that meets it with equal value and slope at ``δ``. The corner angle
    of a triangle is a cone-shaped function of the node positions at 0° and 180° (a squashed triangle can open to
    either side), so ``½ k (α − α0)²`` has a kink there: its gradient jumps, and a Newton step onto a squashed
    sliver cannot be undone by the line search. A function of ``α²`` near 0 (``(π − α)²`` near π) is smooth in the
    positions, so the cap makes the energy C¹ and its slope bounded (→ 0 at the squashed state).
    ``δ = min(1°, α0/2)`` (``min(1°, (π − α0)/2)`` at 180°): the rest angle and everything within half of it are
    untouched, so equilibria away from collapse are exactly Origami Simulator's.
    """
    lo = np.maximum(np.minimum(FACE_SMOOTH, 0.5 * alpha0), 1e-12)
    hi = np.maximum(np.minimum(FACE_SMOOTH, 0.5 * (np.pi - alpha0)), 1e-12)
    dev = alpha - alpha0
    phi = 0.5 * k * dev * dev
    dphi = k * dev
    ddphi = np.full_like(alpha, k)
    low = alpha < lo
    if np.any(low):
        b = k * (lo - alpha0) / (2.0 * lo)
        a = 0.5 * k * (lo - alpha0) ** 2 - b * lo * lo
        phi = np.where(low, a + b * alpha * alpha, phi)
        dphi = np.where(low, 2.0 * b * alpha, dphi)
        ddphi = np.where(low, 2.0 * b, ddphi)
    high = alpha > np.pi - hi
    if np.any(high):
        s = np.pi - alpha
        b = -k * (np.pi - hi - alpha0) / (2.0 * hi)
        a = 0.5 * k * (np.pi - hi - alpha0) ** 2 - b * hi * hi
        phi = np.where(high, a + b * s * s, phi)
        dphi = np.where(high, -2.0 * b * s, dphi)
        ddphi = np.where(high, 2.0 * b, ddphi)
    return phi, dphi, ddphi


def _csqrt_unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``v / |v|`` and ``|v|`` written with analytic operations only (valid for complex-step arguments)."""
    norm = np.sqrt(np.einsum("...k,...k->...", v, v))
    return v / norm[..., None], norm


def hinge_angle_gradient(x1: np.ndarray, x2: np.ndarray, x3: np.ndarray, x4: np.ndarray) -> np.ndarray:
    """``∇θ`` ``(m, 4, 3)`` with respect to wing 1, wing 2, edge node 1, edge node 2 (reference §3.4).

    The same formula as :func:`evaluate` (``n/h`` on the wings, foot fractions ``t`` on the edge nodes), written
    with analytic operations only so that complex-step differentiation gives its exact Jacobian ``∇²θ``.
    """
    e = x4 - x3
    chat, L = _csqrt_unit(e)
    r1, r2 = x1 - x3, x2 - x3
    n1 = _csqrt_unit(_cross(e, r1))[0]  # (v2 − v1) × (w1 − v1): the normal of the face left of v1 → v2
    n2 = _csqrt_unit(_cross(x3 - x4, x2 - x4))[0]
    p1, p2 = _rows_dot(chat, r1), _rows_dot(chat, r2)
    h1 = np.sqrt(_rows_dot(r1, r1) - p1 * p1)
    h2 = np.sqrt(_rows_dot(r2, r2) - p2 * p2)
    t1, t2 = p1 / L, p2 / L
    g1 = n1 / h1[:, None]
    g2 = n2 / h2[:, None]
    g3 = -((1.0 - t1)[:, None] * g1 + (1.0 - t2)[:, None] * g2)
    g4 = -(t1[:, None] * g1 + t2[:, None] * g2)
    return np.stack([g1, g2, g3, g4], axis=1)


def _hinge_curvature_factors(
    x1: np.ndarray, x2: np.ndarray, x3: np.ndarray, x4: np.ndarray, ok: np.ndarray, spare: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """``∇²θ`` of every hinge as a sum of eight outer products: ``X``, ``Y`` ``(m, spare + 8, 12)`` with
    ``∇²θ = Σ_k X[k] Y[k]ᵀ`` (12 = node × component, nodes wing 1, wing 2, edge node 1, edge node 2); the first
    ``spare`` rows are zeros for the caller's own terms (one ``matmul`` then sums everything).

    The closed form of the Jacobian of :func:`hinge_angle_gradient` (same n/h and foot-fraction formula, same signs),
    from differentiating ``g_w = n_w/h_w`` and the foot fractions ``t_w`` directly (equivalent to the dihedral-angle
    Hessian of Tamstorf & Grinspun 2013, "Discrete bending forces and their Jacobians", written per wing). Per wing
    ``w`` (unit normal ``n``, moment arm ``h``, ``m`` the unit vector in the face from the crease line to the wing,
    ``ê`` along the crease, length ``L``): the unit normal of a triangle moves by ``δn = −Σ_b ∇λ_b (n·δx_b)``
    (``λ_b`` its barycentric coordinates, so ``∇λ_wing = m/h``, ``∇λ_v1 = −ê/L − (1 − t) m/h``,
    ``∇λ_v2 = ê/L − t m/h``), ``∂h = m·(δx_wing − (1 − t) δx_v1 − t δx_v2)`` and ``∂t/∂x_v2 = (h m/L − t ê)/L``,
    ``∂t/∂x_wing = ê/L``, ``∂t/∂x_v1 = −∂t/∂x_wing − ∂t/∂x_v2``.
    With the node coefficients of the wing in ``∇θ = Σ_w c⊗n/h``, ``c = (1 at the wing, 0 at the other wing,
    −(1 − t), −t)``, and ``d = (0, 0, −1, 1)`` this gives ::

        ∇²θ = −Σ_w [ (c⊗m)(c⊗n)ᵀ/h² + (c⊗n)(c⊗m)ᵀ/h² + (c⊗ê)(d⊗n)ᵀ/(L h) + (d⊗n)(c⊗ê)ᵀ/(L h) + (d⊗n)(d⊗m)ᵀ/L² ]

    (the last term is not symmetric per wing; its antisymmetric parts cancel between the two wings, since
    ``n1 = ê × m1`` and ``n2 = m2 × ê``). Hinges not ``ok`` (edge or a moment arm below ``HINGE_EPS``) get finite
    values from unit placeholders; callers weight them by zero.
    """
    e = x4 - x3
    L = np.sqrt(_rows_dot(e, e))
    Ls = np.where(ok, L, 1.0)
    chat = e / Ls[:, None]
    X = np.zeros((len(e), spare + 8, 4, 3))
    Y = np.zeros((len(e), spare + 8, 4, 3))
    for w, xw in enumerate((x1, x2)):
        r = xw - x3
        p = _rows_dot(chat, r)
        perp = r - p[:, None] * chat
        h = np.sqrt(_rows_dot(perp, perp))
        hs = np.where(ok, h, 1.0)
        m = perp / hs[:, None]
        n = _cross(chat, m) if w == 0 else _cross(m, chat)
        t = p / Ls
        c = np.zeros((len(e), 4))
        c[:, w] = 1.0
        c[:, 2], c[:, 3] = t - 1.0, -t
        n_h = n / hs[:, None]
        c_m, c_n, c_e = (c[:, :, None] * v[:, None, :] for v in (-m / hs[:, None], n_h, chat / Ls[:, None]))
        k = spare + 4 * w
        # the overall minus sign rides on c_m and on the d⊗n factors (d = (0, 0, −1, 1), so −d⊗n = (0, 0, n, −n))
        X[:, k], Y[:, k] = c_m, c_n
        X[:, k + 1], Y[:, k + 1] = c_n, c_m
        X[:, k + 2] = c_e
        Y[:, k + 2, 2], Y[:, k + 2, 3] = n_h, -n_h
        X[:, k + 3, 2], X[:, k + 3, 3] = n_h, -n_h
        Y[:, k + 3] = c_e
        tail = (hs / (Ls * Ls))[:, None] * m
        Y[:, k + 3, 2] -= tail
        Y[:, k + 3, 3] += tail
    return X.reshape(len(e), spare + 8, 12), Y.reshape(len(e), spare + 8, 12)


def hinge_angle_hessian(
    x1: np.ndarray, x2: np.ndarray, x3: np.ndarray, x4: np.ndarray, weight: np.ndarray | None = None
) -> np.ndarray:
    """``weight · ∇²θ`` ``(m, 4, 4, 3, 3)``, rows ``[node a, node b, i, j]`` (nodes wing 1, wing 2, edge node 1,
    edge node 2), in closed form (:func:`_hinge_curvature_factors`); the Jacobian of :func:`hinge_angle_gradient`.

    Degenerate hinges (edge or a moment arm below ``HINGE_EPS``) get zeros, as :func:`evaluate` skips them.
    The result is a transposed view of ``(m, 4, 3, 4, 3)`` storage.
    """
    r1, r2, e = x1 - x3, x2 - x3, x4 - x3
    L2 = _rows_dot(e, e)
    h1sq = _rows_dot(r1, r1) - _rows_dot(r1, e) ** 2 / np.where(L2 > 0, L2, 1.0)
    h2sq = _rows_dot(r2, r2) - _rows_dot(r2, e) ** 2 / np.where(L2 > 0, L2, 1.0)
    ok = (L2 >= HINGE_EPS**2) & (np.abs(h1sq) >= HINGE_EPS**2) & (np.abs(h2sq) >= HINGE_EPS**2)
    X, Y = _hinge_curvature_factors(x1, x2, x3, x4, ok)
    w = ok.astype(np.float64) if weight is None else np.where(ok, weight, 0.0)
    X *= w[:, None, None]
    return np.matmul(X.transpose(0, 2, 1), Y).reshape(len(e), 4, 3, 4, 3).transpose(0, 1, 3, 2, 4)


def corner_angle_gradient(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """``∂α_corner/∂x_node`` ``(m, 3, 3, 3)`` of the three corner angles of triangles ``(a, b, c)`` (reference §3.5),
    with analytic operations only (for complex-step differentiation)."""
    e_ab, l_ab = _csqrt_unit(b - a)
    e_ac, l_ac = _csqrt_unit(c - a)
    e_bc, l_bc = _csqrt_unit(c - b)
    nrm = _csqrt_unit(_cross(b - a, c - a))[0]
    P_ab = _cross(nrm, e_ab) / l_ab[:, None]
    P_ac = _cross(nrm, e_ac) / l_ac[:, None]
    P_bc = _cross(nrm, e_bc) / l_bc[:, None]
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


def _corner_curvature(x: np.ndarray, tri: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """``Σ_corners weight · ∇²α`` as node blocks ``(t, 3, 3, 3, 3)`` of triangles ``tri``, in closed form.

    For the corner at P between ``u = Q − P`` and ``v = R − P``: ``α = arccos c``, ``c = û·v̂``,
    ``∂c/∂u = q_u = (v̂ − c û)/|u|``, ``∂²c/∂u² = −(û q_uᵀ + q_u ûᵀ + c (I − ûûᵀ)/|u|)/|u|``,
    ``∂²c/∂u∂v = ((I − v̂v̂ᵀ)/|v| − û q_vᵀ)/|u|``, and ``∇²α = −∇²c/sin α − (cos α/sin³α) ∇c∇cᵀ``; node P takes
    ``−(∂u + ∂v)``. (The cap keeps ``weight`` → 0 where ``sin α`` → 0.)
    """
    eye = np.eye(3)
    out = np.zeros((len(tri), 3, 3, 3, 3))
    for corner, (pn, qn, rn) in enumerate(((0, 1, 2), (1, 2, 0), (2, 0, 1))):
        u = x[tri[:, qn]] - x[tri[:, pn]]
        v = x[tri[:, rn]] - x[tri[:, pn]]
        uh, lu = _unit(u)
        vh, lv = _unit(v)
        c = _rows_dot(uh, vh)
        s = np.sqrt(np.maximum(1.0 - c * c, 1e-24))
        qu = (vh - c[:, None] * uh) / lu[:, None]
        qv = (uh - c[:, None] * vh) / lv[:, None]
        uu = uh[:, :, None] * uh[:, None, :]
        vv = vh[:, :, None] * vh[:, None, :]
        cuu = -(
            uh[:, :, None] * qu[:, None, :] + qu[:, :, None] * uh[:, None, :] + (c / lu)[:, None, None] * (eye - uu)
        )
        cuu /= lu[:, None, None]
        cvv = -(
            vh[:, :, None] * qv[:, None, :] + qv[:, :, None] * vh[:, None, :] + (c / lv)[:, None, None] * (eye - vv)
        )
        cvv /= lv[:, None, None]
        cuv = ((eye - vv) / lv[:, None, None] - uh[:, :, None] * qv[:, None, :]) / lu[:, None, None]
        w = weight[:, corner]
        f1 = (-w / s)[:, None, None]
        f2 = (-w * c / s**3)[:, None, None]
        duu = f1 * cuu + f2 * qu[:, :, None] * qu[:, None, :]
        dvv = f1 * cvv + f2 * qv[:, :, None] * qv[:, None, :]
        duv = f1 * cuv + f2 * qu[:, :, None] * qv[:, None, :]
        dvu = duv.transpose(0, 2, 1)
        dpq, dpr = -(duu + dvu), -(duv + dvv)
        out[:, qn, qn] += duu
        out[:, rn, rn] += dvv
        out[:, qn, rn] += duv
        out[:, rn, qn] += dvu
        out[:, pn, qn] += dpq
        out[:, qn, pn] += dpq.transpose(0, 2, 1)
        out[:, pn, rn] += dpr
        out[:, rn, pn] += dpr.transpose(0, 2, 1)
        out[:, pn, pn] += duu + duv + dvu + dvv
    return out


def exact_hessian_blocks(
    model: BarHingeModel, x: np.ndarray, ev: Evaluation
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Element blocks of the exact Hessian ``∇²E`` at ``x`` (``ev`` evaluated there with ``jacobians=True``).

    Returns ``(bars (b, 3, 3), hinges (h, 4, 4, 3, 3), faces (t, 3, 3, 3, 3))``, rows ``[node a, node b, i, j]``:
    bars ``k (d̂d̂ᵀ + (1 − L0/ℓ)(I − d̂d̂ᵀ))`` (the geometric term also where it is negative), hinges
    ``k ∇θ∇θᵀ + k (θ − θ̄) ∇²θ``, faces ``Σ_corners φ''(α) ∇α∇αᵀ + φ'(α) ∇²α``. ``∇²θ``
    (:func:`_hinge_curvature_factors`) and ``∇²α`` (:func:`_corner_curvature`) are in closed form. The Gauss–Newton
    matrix is these without the curvature terms (``θ − θ̄``, ``φ'``) and with the negative bar term dropped. The
    hinge blocks are a transposed view of ``(h, 4, 3, 4, 3)`` storage (``HessianAssembler.assemble_exact`` scatters
    them without a copy).
    """
    i, j = model.bar_nodes[:, 0], model.bar_nodes[:, 1]
    dhat, ell = _unit(x[j] - x[i])
    outer = dhat[:, :, None] * dhat[:, None, :]
    geo = 1.0 - model.bar_length / np.where(ell > 0, ell, 1.0)
    bars = model.bar_k[:, None, None] * (outer + geo[:, None, None] * (np.eye(3) - outer))
    hinges = faces = None
    if ev.hinge_grad is not None and len(model.hinge_k):
        m, k = len(model.hinge_k), ev.hinge_k
        x1, x2 = x[model.hinge_wings[:, 0]], x[model.hinge_wings[:, 1]]
        x3, x4 = x[model.hinge_edge_nodes[:, 0]], x[model.hinge_edge_nodes[:, 1]]
        # k ∇θ∇θᵀ + k (θ − θ̄) ∇²θ as one batched product of (12 × 9)(9 × 12) factors: the Gauss–Newton term
        # first, then the eight terms of ∇²θ (zero weight where k = 0: skipped hinges)
        X, Y = _hinge_curvature_factors(x1, x2, x3, x4, k != 0, spare=1)
        X[:, 1:] *= (k * ev.hinge_dev)[:, None, None]
        g = ev.hinge_grad.reshape(m, 12)
        X[:, 0] = k[:, None] * g
        Y[:, 0] = g
        hinges = np.matmul(X.transpose(0, 2, 1), Y).reshape(m, 4, 3, 4, 3).transpose(0, 1, 3, 2, 4)
    if ev.face_grad is not None:
        fg = ev.face_grad
        faces = np.einsum("tc,tcai,tcbj->tabij", ev.face_ddphi, fg, fg)
        active = np.flatnonzero(np.any(ev.face_dphi != 0, axis=1))
        if len(active):
            faces[active] += _corner_curvature(x, model.triangles[active], ev.face_dphi[active])
    return bars, hinges, faces
