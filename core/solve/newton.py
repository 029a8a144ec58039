"""The fast equilibrium solver: Levenberg–Marquardt-damped Gauss–Newton on the bar-and-hinge energy.

It minimises the same energy as the faithful integrator (``core.forces``) directly instead of integrating damped
dynamics towards it. Each iteration:

1. evaluates the exact forces ``F = −∇E`` and the per-element Jacobians;
2. assembles a positive semi-definite Gauss–Newton Hessian: bar blocks ``k (d̂d̂ᵀ + max(0, 1 − L0/ℓ)(I − d̂d̂ᵀ))``
   (the geometric term is kept where it is positive), ``k ∇θ ∇θᵀ`` per hinge, ``k_f ∇α ∇αᵀ`` per face corner;
3. solves ``(H + λ I) p = F`` (``λ`` is the Levenberg–Marquardt damping, which also removes the six rigid-body null
   modes) by conjugate gradients with matrix-free products ``H v`` (``forces.hessian_matvec``), preconditioned by a
   block-tridiagonal factorisation (``core.solver_linalg``) of an *earlier* ``H + λ I``. The factorisation is
   rebuilt only when CG needs more than ``PCG_MAX`` iterations, so warm-started solves (animation frames, later
   Newton iterations) mostly cost a few matrix-vector products instead of an assembly and a factorisation;
4. accepts ``x + a p`` by an Armijo backtracking line search on the energy (θ unwrapped against the current θ),
   shrinking λ after easy steps and growing it after failures. Steps are capped to a fraction of the model size so
   a 0 → 100 % jump cannot throw hinges through each other in one step.

Near convergence the energy decrease falls under floating-point resolution; there a step is accepted when it
reduces the residual force instead.

Pinned nodes (``fixed``, a boolean mask of degrees of freedom, ``core.solve.constraints``) are fixed degrees of
freedom, not stiff springs: their force is left out of the right-hand side and the residual, their step is zero
(CG runs on the free subspace), and the factorised preconditioner gets a large diagonal there so it decouples them.
The free block is solved exactly as without pins, so pins do not change the order of convergence (quadratic with an
exact Hessian; with the Gauss–Newton one, a pin that turns a rigid motion into a soft pivot slows the tail).
"""

from __future__ import annotations

import time
from collections.abc import Generator
from dataclasses import dataclass

import numpy as np

from .forces import Evaluation, evaluate, hessian_matvec
from .linalg import BlockFactor, BlockTridiagonal
from .model import BarHingeModel

MAX_STEP = 0.25
"""Largest nodal displacement of one Newton step, in normalised units (the model fits in a unit sphere)."""

PCG_MAX = 12
"""CG iterations allowed with a stale preconditioner before the factorisation is rebuilt."""

PCG_RTOL = 1e-2
"""Relative CG residual of the inexact Newton step (the outer iteration corrects what is left)."""

PIN_DIAGONAL = 1e12
"""Diagonal added to fixed degrees of freedom in the factorisation (relative to the force scale): decouples them."""


class HessianAssembler:
    """Scatter indices of every element block into block-tridiagonal storage, computed once per model."""

    def __init__(self, model: BarHingeModel, min_block: int = 24):
        self.model = model
        tri = model.triangles
        wings = model.hinge_wings
        pairs = np.concatenate([model.bar_nodes, tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [0, 2]], wings])
        self.matrix = BlockTridiagonal(model.n_nodes, pairs, min_block)
        i, j = model.bar_nodes[:, 0], model.bar_nodes[:, 1]
        self.bar_index = self.matrix.scatter_index(np.concatenate([i, j, i, j]), np.concatenate([i, j, j, i]))
        hn = np.column_stack([wings, model.hinge_edge_nodes])  # (h, 4): w1, w2, v1, v2
        self.hinge_index = self.matrix.scatter_index(
            np.repeat(hn, 4, axis=1).reshape(-1), np.tile(hn, (1, 4)).reshape(-1)
        ).reshape(len(hn), 4, 4, 3, 3)
        self.face_index = self.matrix.scatter_index(
            np.repeat(tri, 3, axis=1).reshape(-1), np.tile(tri, (1, 3)).reshape(-1)
        ).reshape(len(tri), 3, 3, 3, 3)
        self.assemblies = 0
        self.factor: BlockFactor | None = None
        self.last_cg_iterations = 0

    def assemble(self, ev: Evaluation) -> np.ndarray:
        """Gauss–Newton Hessian storage from an evaluation made with ``jacobians=True``."""
        K = ev.bar_blocks
        idx = [self.bar_index.reshape(-1)]
        vals = [np.concatenate([K, K, -K, -K]).reshape(-1)]
        if ev.hinge_grad is not None:
            g = ev.hinge_grad
            hv = ev.hinge_k[:, None, None, None, None] * g[:, :, None, :, None] * g[:, None, :, None, :]
            idx.append(self.hinge_index.reshape(-1))
            vals.append(hv.reshape(-1))
        if ev.face_grad is not None:
            fv = self.model.face_k * np.einsum("tcai,tcbj->tabij", ev.face_grad, ev.face_grad)
            idx.append(self.face_index.reshape(-1))
            vals.append(fv.reshape(-1))
        self.assemblies += 1
        return self.matrix.assemble(np.concatenate(idx), np.concatenate(vals))


@dataclass
class NewtonStats:
    """Counters of one Newton run (honest accounting for the benchmark)."""

    iterations: int = 0
    force_evaluations: int = 0
    energy_evaluations: int = 0
    hessian_assemblies: int = 0
    linear_solves: int = 0
    hessian_products: int = 0
    converged: bool = False
    residual: float = float("inf")
    message: str = ""


@dataclass
class NewtonProgress:
    """What one Newton iteration leaves behind (yielded by :func:`newton_steps`, e.g. for a progress bar)."""

    iteration: int
    residual: float
    x: np.ndarray
    theta: np.ndarray


def newton_solve(
    model: BarHingeModel,
    x0: np.ndarray,
    theta0: np.ndarray,
    percent: float,
    **options,
) -> tuple[np.ndarray, np.ndarray, Evaluation, NewtonStats, float]:
    """Minimise the energy from ``x0`` (normalised) with fold-angle history ``theta0`` to the end (see
    :func:`newton_steps` for the options). Returns ``(x, theta, evaluation at x, stats, final λ)``."""
    steps = newton_steps(model, x0, theta0, percent, **options)
    while True:
        try:
            next(steps)
        except StopIteration as done:
            return done.value


def newton_steps(
    model: BarHingeModel,
    x0: np.ndarray,
    theta0: np.ndarray,
    percent: float,
    *,
    force_scale: float,
    tolerance: float,
    max_iterations: int,
    assembler: HessianAssembler | None = None,
    time_limit: float | None = None,
    lm_lambda: float = 1e-3,
    fixed: np.ndarray | None = None,
) -> Generator[NewtonProgress, None, tuple[np.ndarray, np.ndarray, Evaluation, NewtonStats, float]]:
    """Minimise the energy from ``x0`` (normalised) with fold-angle history ``theta0``, one iteration per ``next``.

    Yields a :class:`NewtonProgress` after every accepted iteration, so a caller can work in slices (Blender's modal
    jobs) and stop between any two; the generator's return value (``StopIteration.value``) is
    ``(x, theta, evaluation at x, stats, final λ)``. The residual is ``max_i |F_i| / force_scale``.

    ``fixed`` (``(n, 3)`` bool): pinned degrees of freedom; they keep their value in ``x0`` and their (reaction)
    forces are left out of the residual.
    """
    assembler = assembler or HessianAssembler(model)
    stats = NewtonStats()
    t_start = time.perf_counter()
    x = np.array(x0, dtype=np.float64)
    ev = evaluate(model, x, theta0, percent, jacobians=True)
    stats.force_evaluations += 1
    free = None if fixed is None or not np.any(fixed) else ~np.asarray(fixed, dtype=bool).reshape(-1, 3)
    pins = None if free is None else (~free).reshape(-1).astype(np.float64) * PIN_DIAGONAL * force_scale

    def unpinned(forces: np.ndarray) -> np.ndarray:
        return forces if free is None else forces * free

    lam = float(lm_lambda) * force_scale
    lam_min = 1e-9 * force_scale
    for it in range(max_iterations + 1):
        residual = float(np.max(np.linalg.norm(unpinned(ev.forces), axis=1))) / force_scale
        stats.residual = residual
        if not np.isfinite(residual):
            stats.message = f"non-finite residual force at Newton iteration {it}"
            break
        if residual <= tolerance:
            stats.converged = True
            stats.message = f"converged: residual {residual:.2e} ≤ {tolerance:.1e} after {it} iterations"
            break
        if it == max_iterations:
            stats.message = f"not converged: residual {residual:.2e} after {it} iterations (limit)"
            break
        if time_limit is not None and time.perf_counter() - t_start > time_limit:
            stats.message = f"not converged: residual {residual:.2e} after {it} iterations (time limit {time_limit}s)"
            break
        stats.iterations = it + 1
        rhs = unpinned(ev.forces).reshape(-1)
        accepted = False
        for _attempt in range(12):
            try:
                p = _step(model, assembler, ev, rhs, lam, stats, pins).reshape(-1, 3)
            except np.linalg.LinAlgError:
                assembler.factor = None
                lam *= 10.0
                continue
            if not np.all(np.isfinite(p)):
                assembler.factor = None
                lam *= 10.0
                continue
            biggest = float(np.max(np.linalg.norm(p, axis=1)))
            if biggest > MAX_STEP:
                p *= MAX_STEP / biggest
            slope = float(np.dot(rhs, p.reshape(-1)))  # = −∇E·p > 0 for a descent direction
            if slope <= 0:
                lam *= 10.0
                continue
            a = 1.0
            for _ls in range(8):
                trial = x + a * p
                full = _ls == 0  # the full step is usually accepted: evaluate it completely, reused below
                tev = evaluate(model, trial, ev.theta, percent, forces=full, jacobians=full)
                if full:
                    stats.force_evaluations += 1
                else:
                    stats.energy_evaluations += 1
                decrease = ev.energy - tev.energy
                if decrease >= 1e-4 * a * slope:
                    accepted = True
                    break
                if abs(decrease) <= 1e-13 * max(abs(ev.energy), 1e-300) + 1e-300:
                    # energy at round-off level: judge the step by the residual force instead
                    rev = evaluate(model, trial, ev.theta, percent, jacobians=False)
                    stats.force_evaluations += 1
                    if np.max(np.linalg.norm(unpinned(rev.forces), axis=1)) < residual * force_scale:
                        accepted = True
                        break
                a *= 0.5
            if accepted:
                lam = max(lam * (0.3 if a == 1.0 else 1.0), lam_min)
                if a < 0.25:
                    lam *= 4.0
                break
            lam *= 10.0
        if not accepted:
            stats.message = f"stalled: no descent step at Newton iteration {it} (residual {residual:.2e}, λ {lam:.1e})"
            break
        x = trial
        if tev.forces is not None and tev.hinge_grad is not None:
            ev = tev
        else:
            ev = evaluate(model, x, tev.theta, percent, jacobians=True)
            stats.force_evaluations += 1
        yield NewtonProgress(
            it + 1, float(np.max(np.linalg.norm(unpinned(ev.forces), axis=1))) / force_scale, x, ev.theta
        )
    return x, ev.theta, ev, stats, lam / force_scale


def _step(
    model: BarHingeModel,
    assembler: HessianAssembler,
    ev: Evaluation,
    rhs: np.ndarray,
    lam: float,
    stats: NewtonStats,
    pins: np.ndarray | None = None,
) -> np.ndarray:
    """Solve ``(H + λ I) p = rhs``: CG preconditioned by the cached factorisation, refactorised when CG stalls.

    ``pins`` (``3n``, > 0 on fixed degrees of freedom): the step is solved on the free ones only (zero elsewhere)."""
    n = model.n_nodes
    free = None if pins is None else pins == 0

    def project(v: np.ndarray) -> np.ndarray:
        return v if free is None else v * free

    if assembler.factor is not None and assembler.last_cg_iterations < PCG_MAX:
        p = np.zeros_like(rhs)
        r = rhs.copy()
        z = project(assembler.factor.apply(r))
        stats.linear_solves += 1
        d = z.copy()
        rz = float(r @ z)
        goal = PCG_RTOL * float(np.linalg.norm(rhs))
        for cg in range(PCG_MAX):
            assembler.last_cg_iterations = cg + 1
            q = project(hessian_matvec(model, ev, d.reshape(n, 3)).reshape(-1)) + lam * d
            stats.hessian_products += 1
            dq = float(d @ q)
            if dq <= 0 or not np.isfinite(dq):
                break
            a = rz / dq
            p += a * d
            r -= a * q
            if float(np.linalg.norm(r)) <= goal:
                return p
            z = project(assembler.factor.apply(r))
            stats.linear_solves += 1
            rz_new = float(r @ z)
            d = z + (rz_new / rz) * d
            rz = rz_new
    H = assembler.assemble(ev)
    stats.hessian_assemblies += 1
    assembler.factor = assembler.matrix.factor(H, lam if pins is None else lam + pins)
    assembler.last_cg_iterations = 0
    stats.linear_solves += 1
    return project(assembler.factor.apply(rhs))
