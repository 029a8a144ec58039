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

from .model import FLAT_DEAD, BarHingeModel

HINGE_EPS = 1e-6
HINGE_FLOOR = 1e-150
"""Smallest moment arm of a hinge with fading stiffness (``flat_attenuation``): below it ``n/h`` could overflow;
its fading factor there is ~1e-290, so leaving it out changes nothing."""
FACE_EPS = 1e-7

FACE_SMOOTH = np.radians(1.0)
"""Width (rad) of the smooth cap of the face-angle energy at 0° and 180° (see :func:`face_angle_energy`)."""


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
    hinge_fading_gn: np.ndarray | None = None
    """``(len(hinge_fading), 12, 12)``: the positive part of the fading's curvature across each hinge line, added
    to the Gauss–Newton matrix (``HessianAssembler.assemble``)."""
    hinge_fading: np.ndarray | None = None
    """Hinges whose stiffness is fading (a wing in a flat triangle, :func:`flat_attenuation`): their Hessian has
    the terms of the fading factor's derivatives (:func:`_fading_hinge_blocks`)."""


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
        # with fading stiffness a hinge fades out continuously as a wing reaches the hinge line (its energy, force
        # and Hessian → 0 there): skipping it below HINGE_EPS instead made a jump (1e-6 of the energy); only the
        # exact degeneracy, where 1/h overflows, is left out
        arm = HINGE_EPS if model.hinge_flat_scale is None else HINGE_FLOOR
        ok = (L >= HINGE_EPS) & (h1 >= arm) & (h2 >= arm)
        theta = np.where(ok, theta, theta_prev)
        out.theta = theta
        att, (a1, a2), (b11, _, b22) = flat_attenuation(h1, h2, model.hinge_flat_scale)
        k = np.where(ok, model.hinge_k * att, 0.0)
        dev = theta - model.hinge_target * float(percent)
        energy += 0.5 * float(np.dot(k, dev * dev))
        if forces or jacobians:
            Ls = np.where(ok, L, 1.0)
            t1, t2 = p1 / Ls, p2 / Ls
            g1 = n1 / np.where(ok, h1, 1.0)[:, None]
            g2 = n2 / np.where(ok, h2, 1.0)[:, None]
            g3 = -((1.0 - t1)[:, None] * g1 + (1.0 - t2)[:, None] * g2)
            g4 = -(t1[:, None] * g1 + t2[:, None] * g2)
            f = np.flatnonzero(ok & ((a1 != 0) | (a2 != 0)))  # hinges whose stiffness is fading
            if len(f):  # ∇h_w = c_w ⊗ m_w, c_w = (1 at wing w, 0 at the other, −(1 − t_w), −t_w), m_w ⟂ the edge
                half = 0.5 * model.hinge_k[f] * dev[f] ** 2
                grad_h = np.zeros((2, len(f), 4, 3))
                for w, (r, p_, t) in enumerate(((r1, p1, t1), (r2, p2, t2))):
                    perp = r[f] - p_[f, None] * chat[f]
                    m_w = perp / np.linalg.norm(perp, axis=1)[:, None]  # the unit moment arm, from the line to wing w
                    grad_h[w, :, w] = m_w
                    grad_h[w, :, 2] = -(1.0 - t[f, None]) * m_w
                    grad_h[w, :, 3] = -t[f, None] * m_w
            if forces:
                tau = (-k * dev)[:, None]
                idx_parts += [w1, w2, v1, v2]
                val_parts += [tau * g1, tau * g2, tau * g3, tau * g4]
                if len(f):  # −½ k₀ dev² ∇att, ∇att = a1 ∇h1 + a2 ∇h2
                    q = -half[:, None, None] * (a1[f, None, None] * grad_h[0] + a2[f, None, None] * grad_h[1])
                    idx_parts += [w1[f], w2[f], v1[f], v2[f]]
                    val_parts += [q[:, 0], q[:, 1], q[:, 2], q[:, 3]]
            if jacobians:
                out.hinge_grad = np.stack([g1, g2, g3, g4], axis=1)
                out.hinge_k = k
                out.hinge_dev = dev
                out.hinge_fading = f
                if len(f):
                    # the fading's own stiffness across the hinge line, ½ k₀ dev² σ''(u)/s² ∇h∇hᵀ where positive (as
                    # the wing nears the line): Gauss–Newton must see it, its length scale is the fading's
                    g = grad_h.reshape(2, len(f), 12)
                    c1 = half * np.maximum(b11[f], 0.0)
                    c2 = half * np.maximum(b22[f], 0.0)
                    out.hinge_fading_gn = (
                        c1[:, None, None] * g[0][:, :, None] * g[0][:, None, :]
                        + c2[:, None, None] * g[1][:, :, None] * g[1][:, None, :]
                    )

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


def flat_attenuation(
    h1: np.ndarray, h2: np.ndarray, scale: np.ndarray | None
) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The factor ``att = σ(h1/s1) σ(h2/s2)`` a hinge's stiffness is multiplied by, with its first and second
    derivatives in the moment arms: ``(att, (∂att/∂h1, ∂att/∂h2), (∂²/∂h1², ∂²/∂h1∂h2, ∂²/∂h2²))``.

    ``s`` = ``model.hinge_flat_scale`` (:data:`.model.FLAT_RATIO` times the shortest side of the wing's triangle at
    rest, or :data:`.model.FLAT_FRACTION` of its rest moment arm if less); ``σ(u) = 10u³ − 15u⁴ + 6u⁵`` of
    ``u = (h/s − d)/(1 − d)`` clipped to [0, 1], ``d`` = :data:`.model.FLAT_DEAD`: C² at both ends. A hinge whose
    wings are not squashed that close to its line is Origami Simulator's exactly; one whose wing is within ``d·s`` of
    it has no stiffness (its triangle is pressed flat and has no dihedral angle), so the energy stays C² when the
    triangle turns inside out (the fold angle jumps by 180° there) and force and Hessian vanish before ``k ∇θ``
    (∝ 1/h) and ``k ∇θ∇θᵀ`` (∝ 1/h²) grow. With ``σ = 3u² − 2u³`` from the line itself (C¹, the fourth pass) the
    Hessian stayed ~k₀/s² there and its derivative grew as 1/h: Newton's model held only within ~h of a squashed
    triangle (1e-10), and folds that pressed one flat stalled; with the C² fading alone, a flat triangle's last
    stiffness turned its free plane about the line 0.25° per iteration (docs/solver.md). ``scale`` ``None``: no
    fading (ones and zeros)."""
    if scale is None:
        one, zero = np.ones_like(h1), np.zeros_like(h1)
        return one, (zero, zero), (zero, zero, zero)

    def smootherstep(h: np.ndarray, full: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        s = (1.0 - FLAT_DEAD) * full  # σ rises from 0 at FLAT_DEAD·full to 1 at full
        u = np.clip((h - FLAT_DEAD * full) / s, 0.0, 1.0)
        w = 1.0 - u
        inside = (u < 1.0) & (u > 0.0)
        return (
            u * u * u * (10.0 - 15.0 * u + 6.0 * u * u),
            np.where(inside, 30.0 * u * u * w * w / s, 0.0),
            np.where(inside, 60.0 * u * w * (1.0 - 2.0 * u) / (s * s), 0.0),
        )

    f1, d1, dd1 = smootherstep(h1, scale[:, 0])
    f2, d2, dd2 = smootherstep(h2, scale[:, 1])
    return f1 * f2, (d1 * f2, f1 * d2), (dd1 * f2, d1 * d2, f1 * dd2)


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


def _matvec_index(model: BarHingeModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(hinge nodes (h, 4), flat dof index, bincount length)`` of :func:`hessian_matvec`'s single scatter, built
    once per model and kept on it: bar nodes i then j, hinge nodes row by row, triangle nodes row by row."""
    cached = model.__dict__.get("_matvec_index")
    if cached is None:
        hn = np.column_stack([model.hinge_wings, model.hinge_edge_nodes]).astype(np.int64)
        nodes = np.concatenate(
            [model.bar_nodes[:, 0], model.bar_nodes[:, 1], hn.reshape(-1), model.triangles.reshape(-1)]
        )
        flat = (nodes[:, None] * 3 + np.arange(3)).reshape(-1)
        cached = (hn, flat, 3 * model.n_nodes)
        model.__dict__["_matvec_index"] = cached
    return cached


def hessian_matvec(model: BarHingeModel, ev: Evaluation, v: np.ndarray) -> np.ndarray:
    """Gauss–Newton Hessian (the PSD blocks of ``ev``, see ``core.solve.newton``) times ``v`` (``(n, 3)``).

    Element by element, without assembling a matrix: bars ``K_b (v_j − v_i)``, hinges ``k ∇θ (∇θ·v)``, faces
    ``k_f Σ ∇α (∇α·v)``, summed into the nodes by one ``bincount`` over a precomputed index. Used by the power
    iteration of the faithful integrator's time-step bound (and by the tests, against the assembled matrix).
    """
    hn, flat, size = _matvec_index(model)
    i, j = model.bar_nodes[:, 0], model.bar_nodes[:, 1]
    fb = np.einsum("bij,bj->bi", ev.bar_blocks, v[j] - v[i])
    vals = [-fb, fb]
    if ev.hinge_grad is not None and len(ev.hinge_k):
        g = ev.hinge_grad
        s = ev.hinge_k * np.einsum("hak,hak->h", g, v[hn])
        vals.append((s[:, None, None] * g).reshape(-1, 3))
    else:
        vals.append(np.zeros((4 * len(hn), 3)))
    if ev.face_grad is not None:
        fg = ev.face_grad
        c = model.face_k * np.einsum("tcak,tak->tc", fg, v[model.triangles])
        vals.append(np.einsum("tc,tcak->tak", c, fg).reshape(-1, 3))
    else:
        vals.append(np.zeros((3 * len(model.triangles), 3)))
    return np.bincount(flat, weights=np.concatenate(vals).reshape(-1), minlength=size).reshape(-1, 3)


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


def _dot3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Column-wise dot product of ``(3, m)`` arrays (components first: every operation runs over ``m``)."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Column-wise cross product of ``(3, m)`` arrays."""
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _scratch(work: dict[str, np.ndarray] | None, name: str, shape: tuple[int, ...], zero: bool = False) -> np.ndarray:
    """Array ``work[name]`` of ``shape``, made on first use and reused by later calls (``zero``: cleared), or a new
    array without ``work``. Reuse matters: a fresh array of megabytes costs its page faults on every call."""
    if work is None:
        return np.zeros(shape) if zero else np.empty(shape)
    a = work.get(name)
    if a is None or a.shape != shape:
        a = work[name] = np.empty(shape)
    if zero:
        a.fill(0.0)
    return a


def _outer_sum(X: np.ndarray, Y: np.ndarray, work: dict[str, np.ndarray] | None = None, name: str = "") -> np.ndarray:
    """``Σ_k X[k] Y[k]ᵀ`` per element: ``X``, ``Y`` ``(K, q, 3, m)`` (term, node, component, element) →
    ``(m, q, q, 3, 3)`` rows ``[node a, node b, i, j]``, a transposed view of ``(m, q, 3, q, 3)`` storage
    (``work[name + "out"]`` when ``work`` is given).

    The factors are built components-first (numpy is slow on a trailing axis of 3); one transposing copy of each
    and one batched ``matmul`` of ``(3q × K)(K × 3q)`` matrices make the blocks.
    """
    K, q, _, m = X.shape
    A = _scratch(work, name + "A", (m, 3 * q, K))
    B = _scratch(work, name + "B", (m, K, 3 * q))
    np.copyto(A, X.reshape(K, 3 * q, m).transpose(2, 1, 0))
    np.copyto(B, Y.reshape(K, 3 * q, m).transpose(2, 0, 1))
    out = np.matmul(A, B, out=_scratch(work, name + "out", (m, 3 * q, 3 * q)))
    return out.reshape(m, q, 3, q, 3).transpose(0, 1, 3, 2, 4)


def _hinge_curvature_factors(
    x1: np.ndarray,
    x2: np.ndarray,
    x3: np.ndarray,
    x4: np.ndarray,
    ok: np.ndarray,
    spare: int = 0,
    work: dict[str, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """``∇²θ`` of every hinge as a sum of eight outer products: from node positions ``(3, m)`` (components first)
    of wing 1, wing 2, edge node 1, edge node 2, ``X``, ``Y`` ``(spare + 8, 4, 3, m)`` with
    ``∇²θ = Σ_k X[k] Y[k]ᵀ`` (see :func:`_outer_sum`); the first ``spare`` terms are zeros for the caller's own.

    The closed form of the Jacobian of the hinge gradient of :func:`evaluate` (same n/h and foot-fraction formula, same
    signs),
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
    m = x1.shape[1]
    e = x4 - x3
    Ls = np.where(ok, np.sqrt(_dot3(e, e)), 1.0)
    chat = e / Ls
    e_L = chat / Ls
    X = _scratch(work, "hinge X", (spare + 8, 4, 3, m), zero=True)
    Y = _scratch(work, "hinge Y", (spare + 8, 4, 3, m), zero=True)
    for w, xw in enumerate((x1, x2)):
        r = xw - x3
        p = _dot3(chat, r)
        perp = r - p * chat
        hs = np.where(ok, np.sqrt(_dot3(perp, perp)), 1.0)
        unit_m = perp / hs
        n = _cross3(chat, unit_m) if w == 0 else _cross3(unit_m, chat)
        t = p / Ls
        n_h = n / hs
        c = np.zeros((4, 1, m))
        c[w] = 1.0
        c[2, 0], c[3, 0] = t - 1.0, -t
        k = spare + 4 * w
        # the overall minus sign rides on the c⊗m factor and on the d⊗n factors (−d⊗n = (0, 0, n, −n))
        X[k] = c * (-unit_m / hs)
        Y[k] = c * n_h
        X[k + 1], Y[k + 1] = Y[k], X[k]
        X[k + 2] = c * e_L
        Y[k + 2, 2], Y[k + 2, 3] = n_h, -n_h
        X[k + 3, 2], X[k + 3, 3] = n_h, -n_h
        tail = unit_m * (hs / (Ls * Ls))
        Y[k + 3] = X[k + 2]
        Y[k + 3, 2] -= tail
        Y[k + 3, 3] += tail
    return X, Y


def hinge_angle_hessian(
    x1: np.ndarray, x2: np.ndarray, x3: np.ndarray, x4: np.ndarray, weight: np.ndarray | None = None
) -> np.ndarray:
    """``weight · ∇²θ`` ``(m, 4, 4, 3, 3)``, rows ``[node a, node b, i, j]`` (nodes wing 1, wing 2, edge node 1,
    edge node 2, positions ``(m, 3)``), in closed form (:func:`_hinge_curvature_factors`): the Jacobian of the hinge
    gradient ``n/h`` of :func:`evaluate` (tests/test_hinge_hessian.py checks it against complex steps). Degenerate
    hinges (edge or a moment arm below ``HINGE_EPS``) get zeros, as :func:`evaluate` skips them.
    """
    x1, x2, x3, x4 = (np.ascontiguousarray(v.T) for v in (x1, x2, x3, x4))
    r1, r2, e = x1 - x3, x2 - x3, x4 - x3
    L2 = _dot3(e, e)
    L2s = np.where(L2 > 0, L2, 1.0)
    h1sq = _dot3(r1, r1) - _dot3(r1, e) ** 2 / L2s
    h2sq = _dot3(r2, r2) - _dot3(r2, e) ** 2 / L2s
    ok = (L2 >= HINGE_EPS**2) & (np.abs(h1sq) >= HINGE_EPS**2) & (np.abs(h2sq) >= HINGE_EPS**2)
    X, Y = _hinge_curvature_factors(x1, x2, x3, x4, ok)
    X *= ok if weight is None else np.where(ok, weight, 0.0)
    return _outer_sum(X, Y)


FACE_EDGES = ((1, 2), (2, 0), (0, 1))
"""The edges of a triangle ``(nodes 0, 1, 2)``, edge ``m`` opposite node ``m``, from its first node to its second."""


def _face_length_hessian(
    xt: np.ndarray, triangles: np.ndarray, dphi: np.ndarray, ddphi: np.ndarray, out: np.ndarray
) -> np.ndarray:
    """``Σ_corners φ''(α) ∇α∇αᵀ + φ'(α) ∇²α`` of every triangle, through its edge lengths, written into ``out``
    ``(t, 9, 9)`` (rows ``[node a, component i]``, columns ``[node b, component j]``); returns ``out``.

    ``xt`` ``(3, n)`` node positions components first, ``dphi``, ``ddphi`` ``(3, t)`` the energy's slopes ``φ'``,
    ``φ''`` per corner (zero on skipped triangles). A corner angle depends on the three edge lengths ``l`` only, so
    the face energy is ``Ψ(l) = Σ_i φ(α_i(l))`` and its Hessian is ``J_lᵀ ∇²Ψ J_l + Σ_m ∂Ψ/∂l_m ∇²l_m``: ``J_l`` the
    three edge-length gradients (``±d̂_m`` at the edge's nodes), ``∇²l_m = (I − d̂_m d̂_mᵀ)/l_m`` on the edge's node
    pair as for a bar. With ``C_i = cos α_i = (l_j² + l_k² − l_i²)/(2 l_j l_k)`` (``l_i`` opposite corner ``i``),
    ``s_i = sin α_i = 2A/(l_j l_k)``, ``∂α = −∂C/s`` and ``∂²α = −∂²C/s − (C/s³) ∂C∂Cᵀ``::

        ∂Ψ/∂l = Σ_i −(φ'_i/s_i) ∂C_i,    ∇²Ψ = Σ_i (φ''_i − φ'_i C_i/s_i)/s_i² ∂C_i∂C_iᵀ − (φ'_i/s_i) ∂²C_i

    with ``∂C/∂l_i = −l_i/(l_j l_k)``, ``∂C/∂l_j = 1/l_k − C/l_j``, ``∂²C/∂l_i² = −1/(l_j l_k)``,
    ``∂²C/∂l_i∂l_j = l_i/(l_j² l_k)``, ``∂²C/∂l_j² = 2C/l_j² − 1/(l_j l_k)``, ``∂²C/∂l_j∂l_k = C/(l_j l_k) − 1/l_j²
    − 1/l_k²`` (``j``, ``k`` symmetric). Three rank-one terms and three bar-like blocks per triangle instead of the
    thirty rank-one terms of the corner-angle form it replaced (sixth pass: 7.2 → ~3 ms at 3,000 faces, equal to
    1e-15; tests/test_hinge_hessian.py holds it to the complex-step curvature, squashed corners included). The cap
    keeps ``φ'`` → 0 where ``s`` → 0; ``s`` is floored at 1e-12 as a guard.
    """
    t = len(triangles)
    P = [xt[:, triangles[:, q]] for q in range(3)]
    d, ln = [], []
    for a, b in FACE_EDGES:
        e = P[b] - P[a]
        length = np.sqrt(_dot3(e, e))
        length = np.where(length > 0, length, 1.0)
        d.append(e / length)
        ln.append(length)
    cross = _cross3(P[1] - P[0], P[2] - P[0])
    twice_area = np.sqrt(_dot3(cross, cross))
    psi1 = np.zeros((3, t))  # ∂Ψ/∂l_m
    psi2 = np.zeros((3, 3, t))  # ∂²Ψ/∂l_m∂l_n
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        li, lj, lk = ln[i], ln[j], ln[k]
        cos = -_dot3(d[k], d[j])  # the corner at node i between edge k (towards node j) and edge j (from node k)
        sin = np.maximum(twice_area / (lj * lk), 1e-12)
        g = {i: -li / (lj * lk), j: 1.0 / lk - cos / lj, k: 1.0 / lj - cos / lk}  # ∂C_i/∂l
        inv_jk = 1.0 / (lj * lk)
        h = {
            (i, i): -inv_jk,
            (i, j): li / (lj * lj * lk),
            (i, k): li / (lj * lk * lk),
            (j, j): 2.0 * cos / (lj * lj) - inv_jk,
            (k, k): 2.0 * cos / (lk * lk) - inv_jk,
            (j, k): cos * inv_jk - 1.0 / (lj * lj) - 1.0 / (lk * lk),
        }
        slope = -dphi[i] / sin
        curve = (ddphi[i] + slope * cos) / (sin * sin)
        for m in range(3):
            psi1[m] += slope * g[m]
        for (m, n), hmn in h.items():
            term = curve * g[m] * g[n] + slope * hmn
            psi2[m, n] += term
            if m != n:
                psi2[n, m] += term
    J = np.zeros((t, 3, 9))  # ∂l_m/∂x_(node, component)
    for m, (a, b) in enumerate(FACE_EDGES):
        J[:, m, 3 * b : 3 * b + 3] = d[m].T
        J[:, m, 3 * a : 3 * a + 3] = -d[m].T
    np.matmul(J.transpose(0, 2, 1), np.matmul(np.ascontiguousarray(psi2.transpose(2, 0, 1)), J), out=out)
    blocks = out.reshape(t, 3, 3, 3, 3)  # [t, a, i, b, j]
    eye = np.eye(3)
    for m, (a, b) in enumerate(FACE_EDGES):
        dm = d[m].T
        K = (psi1[m] / ln[m])[:, None, None] * (eye - dm[:, :, None] * dm[:, None, :])
        blocks[:, a, :, a, :] += K
        blocks[:, b, :, b, :] += K
        blocks[:, a, :, b, :] -= K
        blocks[:, b, :, a, :] -= K
    return out


def _fading_hinge_blocks(model: BarHingeModel, xt: np.ndarray, ev: Evaluation, f: np.ndarray) -> np.ndarray:
    """What the fading stiffness ``k₀ att(h1, h2)`` (:func:`flat_attenuation`) adds to the Hessian of the hinges
    ``f`` beyond ``k ∇θ∇θᵀ + k (θ − θ̄) ∇²θ`` (with ``k = k₀ att``), ``(len(f), 4, 4, 3, 3)``:
    ``k₀ (θ − θ̄) (∇att ∇θᵀ + ∇θ ∇attᵀ) + ½ k₀ (θ − θ̄)² ∇²att``, in closed form.

    Per wing (nodes wing 1, wing 2, edge node 1, edge node 2; ``c`` the wing's coefficients ``(1 at the wing, 0,
    −(1 − t), −t)``, ``d = (0, 0, −1, 1)``, ``m`` the unit vector from the hinge line to the wing, ``ê`` along the
    edge of length ``L``, ``n = ê × m``): ``∇h = c⊗m`` and ``∇²h = (c⊗n)(c⊗n)ᵀ/h − [(c⊗ê)(d⊗m)ᵀ + (d⊗m)(c⊗ê)ᵀ]/L
    − (h/L²)(d⊗m)(d⊗m)ᵀ`` (the second variation of the distance to a line through two moving points); ``∇att`` and
    ``∇²att`` follow by the chain rule from the derivatives :func:`flat_attenuation` returns."""
    wings, edge = model.hinge_wings[f], model.hinge_edge_nodes[f]
    x3, x4 = xt[:, edge[:, 0]], xt[:, edge[:, 1]]
    e = x4 - x3
    L = np.sqrt(_dot3(e, e))
    chat = e / L
    ms = len(f)
    d = np.zeros((4, 1, ms))
    d[2], d[3] = -1.0, 1.0
    per_wing = []
    for w in range(2):
        r = xt[:, wings[:, w]] - x3
        p = _dot3(chat, r)
        perp = r - p * chat
        h = np.sqrt(_dot3(perp, perp))
        m = perp / h
        t = p / L
        c = np.zeros((4, 1, ms))
        c[w] = 1.0
        c[2, 0], c[3, 0] = t - 1.0, -t
        per_wing.append((h, c * m, c * _cross3(chat, m), c * chat, d * m))
    (h1, G1, N1, E1, M1), (h2, G2, N2, E2, M2) = per_wing
    _, (a1, a2), (b11, b12, b22) = flat_attenuation(h1, h2, model.hinge_flat_scale[f])
    k0, dev = model.hinge_k[f], ev.hinge_dev[f]
    A, B = k0 * dev, 0.5 * k0 * dev * dev
    grad_theta = ev.hinge_grad[f].transpose(1, 2, 0)  # (4, 3, ms)
    grad_att = a1 * G1 + a2 * G2
    terms = [
        (A * grad_att, grad_theta),
        (grad_theta, A * grad_att),
        (B * b11 * G1, G1),
        (B * b22 * G2, G2),
        (B * b12 * G1, G2),
        (B * b12 * G2, G1),
    ]
    for a, h, N, E, M in ((a1, h1, N1, E1, M1), (a2, h2, N2, E2, M2)):
        terms += [(B * a / h * N, N), (-B * a / L * E, M), (-B * a / L * M, E), (-B * a * h / (L * L) * M, M)]
    X = np.stack([x for x, _ in terms])
    Y = np.stack([y for _, y in terms])
    return _outer_sum(X, Y)


def exact_hessian_blocks(
    model: BarHingeModel, x: np.ndarray, ev: Evaluation, work: dict[str, np.ndarray] | None = None
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Element blocks of the exact Hessian ``∇²E`` at ``x`` (``ev`` evaluated there with ``jacobians=True``).

    Returns ``(bars (b, 3, 3), hinges (h, 4, 4, 3, 3), faces (t, 3, 3, 3, 3))``, rows ``[node a, node b, i, j]``:
    bars ``k (d̂d̂ᵀ + (1 − L0/ℓ)(I − d̂d̂ᵀ))`` (the geometric term also where it is negative), hinges
    ``k ∇θ∇θᵀ + k (θ − θ̄) ∇²θ``, faces ``Σ_corners φ''(α) ∇α∇αᵀ + φ'(α) ∇²α``, all in closed form
    (:func:`_hinge_curvature_factors` with one batched product of the outer-product factors, :func:`_outer_sum`;
    :func:`_face_length_hessian` through the triangles' edge lengths). The Gauss–Newton matrix is these without the
    curvature terms (``θ − θ̄``, ``φ'``) and with the negative bar term dropped. The hinge and face blocks are
    transposed views of ``(·, q, 3, q, 3)`` storage (``HessianAssembler.assemble_exact`` scatters them without a
    copy). ``work`` (a dict the caller keeps) holds the large scratch arrays between calls; the returned blocks then
    live in it and are valid until the next call with it.
    """
    i, j = model.bar_nodes[:, 0], model.bar_nodes[:, 1]
    dhat, ell = _unit(x[j] - x[i])
    outer = dhat[:, :, None] * dhat[:, None, :]
    geo = 1.0 - model.bar_length / np.where(ell > 0, ell, 1.0)
    bars = model.bar_k[:, None, None] * (outer + geo[:, None, None] * (np.eye(3) - outer))
    hinges = faces = None
    xt = np.ascontiguousarray(x.T)  # components first for the element factors
    if ev.hinge_grad is not None and len(model.hinge_k):
        m, k = len(model.hinge_k), ev.hinge_k
        wings, edge = model.hinge_wings, model.hinge_edge_nodes
        # k ∇θ∇θᵀ + k (θ − θ̄) ∇²θ in one batched product: the Gauss–Newton term first, then the eight terms of
        # ∇²θ (weight zero where k = 0: skipped hinges)
        X, Y = _hinge_curvature_factors(
            xt[:, wings[:, 0]], xt[:, wings[:, 1]], xt[:, edge[:, 0]], xt[:, edge[:, 1]], k != 0, 1, work
        )
        X[1:] *= k * ev.hinge_dev
        g = ev.hinge_grad.reshape(m, 12).T.reshape(4, 3, m)
        X[0] = k * g
        Y[0] = g
        hinges = _outer_sum(X, Y, work, "hinge ")
        fading = ev.hinge_fading
        if fading is not None and len(fading):
            hinges[fading] += _fading_hinge_blocks(model, xt, ev, fading)
    if ev.face_grad is not None:
        tri, t = model.triangles, len(model.triangles)
        out = _scratch(work, "face out", (t, 9, 9))
        _face_length_hessian(xt, tri, ev.face_dphi.T, ev.face_ddphi.T, out)
        faces = out.reshape(t, 3, 3, 3, 3).transpose(0, 1, 3, 2, 4)
    return bars, hinges, faces
