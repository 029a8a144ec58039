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
        dev = np.where(ok[:, None], alpha - model.face_alpha0, 0.0)
        energy += 0.5 * model.face_k * float(np.sum(dev * dev))
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
    """Gauss–Newton Hessian (the PSD blocks of ``ev``, see ``core.solver_newton``) times ``v`` (``(n, 3)``).

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
