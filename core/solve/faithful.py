"""The faithful solver: Origami Simulator's explicit damped dynamics, stepped in numpy (reference §3.6–3.8).

Unit masses, all forces computed from the state at step n (Jacobi style, as on the GPU), then semi-implicit
(symplectic) Euler: ``v ← v + dt·F(x, v)``, ``x ← x + dt·v``. The only damping is the bar term
``c (v_j − v_i)`` on the full relative velocity. The sheet floats free (no fixed node).

Time step. Origami Simulator uses ``dt = 0.9 / (2π √(k_axial / L0_min))`` and ignores hinge (``k/h²``) and face
(``k_f/ℓ²``) stiffness, which makes skinny triangles explode (reference §3.7, §9.1). The default rule here,
``"all_terms"``, uses the exact stability limit of semi-implicit Euler with damping: a mode with stiffness ω² and
damping γ is stable iff ``dt² ω² + 2 dt γ < 4``, i.e. ``dt < 2 / (γ/2 + √(γ²/4 + ω²))``. ω² and γ are the
largest eigenvalues of the stiffness matrix (bars + hinges + face springs, Gauss–Newton blocks at rest) and of the
damping matrix, found by power iteration (×1.05 slack), and ``dt`` is that limit × ``safety`` (0.9). On the
fixtures this is 1.1–2× Origami Simulator's dt where theirs is stable, and smaller where theirs explodes.
``"gershgorin"`` is the older, provably safe but ~3× smaller bound (block row sums, ``safety/(√λ_K + λ_C/2)``);
``"origami_simulator"`` reproduces the original.

Why the faithful run is slow (measured, see docs/solver.md): the damping acts on the *full* relative velocity of
every bar, so it also damps rigid rotation of a panel about a crease. Folding a crease or bending a panel is then
heavily over-damped: its relaxation time is about ``Σ c ℓ² / k_hinge`` (hundreds of time units), i.e. 10⁴–10⁵
steps per e-fold (simpleVertex: 27,000). The integrator is correct; it creeps to the fast solver's equilibrium.

Divergence (non-finite positions or velocities, a node leaving a sphere 50× the model, or a node moving more than
the model's radius in one step; checked every ``check_every`` steps) raises :class:`SolverError` naming the step,
dt and the quantity.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .forces import damping_forces, damping_matvec, evaluate, hessian_matvec
from .model import BarHingeModel


class SolverError(RuntimeError):
    """The solver diverged or was given an unusable state; the message names the step and the quantity."""


@dataclass
class FaithfulStats:
    steps: int = 0
    force_evaluations: int = 0
    converged: bool = False
    residual: float = float("inf")
    message: str = ""


def stiffness_bound(model: BarHingeModel) -> tuple[float, float]:
    """Gershgorin bounds ``(λ_K, λ_C)`` on the stiffness and damping matrices at the flat rest state."""
    ev = evaluate(model, model.rest, None, 0.0, forces=False, jacobians=True)
    n = model.n_nodes
    i, j = model.bar_nodes[:, 0], model.bar_nodes[:, 1]
    row = np.bincount(np.concatenate([i, j]), weights=np.tile(2.0 * model.bar_k, 2), minlength=n)
    if ev.hinge_grad is not None and len(ev.hinge_k):
        gn = np.linalg.norm(ev.hinge_grad, axis=2)  # (h, 4)
        contrib = ev.hinge_k[:, None] * gn * gn.sum(axis=1, keepdims=True)
        nodes = np.column_stack([model.hinge_wings, model.hinge_edge_nodes])
        row += np.bincount(nodes.reshape(-1), weights=contrib.reshape(-1), minlength=n)
    if ev.face_grad is not None:
        gn = np.linalg.norm(ev.face_grad, axis=3)  # (t, corner, node)
        contrib = model.face_k * np.einsum("tca,tc->ta", gn, gn.sum(axis=2))
        row += np.bincount(model.triangles.reshape(-1), weights=contrib.reshape(-1), minlength=n)
    damp = np.bincount(np.concatenate([i, j]), weights=np.tile(2.0 * model.bar_c, 2), minlength=n)
    return float(row.max()), float(damp.max())


def _largest_eigenvalue(matvec, n: int, iterations: int = 120, seed: int = 0) -> float:
    """Largest eigenvalue of a symmetric PSD operator on ``(n, 3)`` arrays by power iteration (a lower bound)."""
    x = np.random.default_rng(seed).normal(size=(n, 3))
    lam = 0.0
    for _ in range(iterations):
        y = matvec(x)
        norm = float(np.linalg.norm(y))
        if norm == 0 or not np.isfinite(norm):
            return lam
        lam = norm / float(np.linalg.norm(x))
        x = y / norm
    return lam


def spectral_bounds(model: BarHingeModel) -> tuple[float, float]:
    """``(λ_K, λ_C)``: largest eigenvalues of the stiffness and damping matrices at the flat rest state (×1.05)."""
    ev = evaluate(model, model.rest, None, 0.0, forces=False, jacobians=True)
    lam_k = _largest_eigenvalue(lambda v: hessian_matvec(model, ev, v), model.n_nodes)
    lam_c = _largest_eigenvalue(lambda v: damping_matvec(model, v), model.n_nodes)
    return 1.05 * lam_k, 1.05 * lam_c


def time_step(
    model: BarHingeModel, rule: str = "all_terms", safety: float = 0.9, axial_stiffness: float = 20.0
) -> float:
    """The explicit time step for ``model`` (normalised units, unit masses); see the module docstring."""
    if rule == "origami_simulator":
        return 0.9 / (2.0 * np.pi * np.sqrt(axial_stiffness / float(model.bar_length.min())))
    if rule == "gershgorin":
        lam_k, lam_c = stiffness_bound(model)
        return safety / (np.sqrt(lam_k) + 0.5 * lam_c)
    if rule != "all_terms":
        raise ValueError(f"unknown dt_rule {rule!r}: use 'all_terms', 'gershgorin' or 'origami_simulator'")
    lam_k, lam_c = spectral_bounds(model)
    return safety * 2.0 / (0.5 * lam_c + np.sqrt(0.25 * lam_c * lam_c + lam_k))


def faithful_solve(
    model: BarHingeModel,
    x0: np.ndarray,
    v0: np.ndarray,
    theta0: np.ndarray,
    percent: float,
    *,
    dt: float,
    force_scale: float,
    tolerance: float,
    max_steps: int,
    check_every: int = 100,
    time_limit: float | None = None,
    stop_on_convergence: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, FaithfulStats]:
    """Integrate from ``(x0, v0, θ0)`` for at most ``max_steps`` steps; returns ``(x, v, θ, stats)``.

    Every ``check_every`` steps the static residual ``max_i |F_i| / force_scale`` (damping excluded) is compared with
    ``tolerance``; with ``stop_on_convergence`` the run stops there.
    """
    stats = FaithfulStats()
    x = np.array(x0, dtype=np.float64)
    v = np.array(v0, dtype=np.float64)
    theta = np.array(theta0, dtype=np.float64)
    limit = 50.0
    t0 = time.perf_counter()
    check = max(int(check_every), 1)
    for step in range(1, max_steps + 1):
        if step % check == 0 or step == max_steps:
            ev = evaluate(model, x, theta, percent)
            stats.force_evaluations += 1
            f = ev.forces
            stats.residual = float(np.max(np.linalg.norm(f, axis=1))) / force_scale
            f = f + damping_forces(model, v)
            if stats.residual <= tolerance and stop_on_convergence:
                stats.steps = step - 1
                stats.converged = True
                stats.message = f"converged: residual {stats.residual:.2e} ≤ {tolerance:.1e} after {step - 1} steps"
                return x, v, ev.theta, stats
            if time_limit is not None and time.perf_counter() - t0 > time_limit:
                stats.steps = step - 1
                stats.message = (
                    f"capped: residual {stats.residual:.2e} after {step - 1} steps (time limit {time_limit:g} s)"
                )
                return x, v, ev.theta, stats
        else:
            # one scatter for elastic and damping forces (the hot path)
            ev = evaluate(model, x, theta, percent, damping_velocity=v)
            stats.force_evaluations += 1
            f = ev.forces
        theta = ev.theta
        v = v + dt * f
        x = x + dt * v
        if step % check == 0 or step == max_steps:
            biggest = float(np.max(np.abs(x)))
            speed = float(np.max(np.abs(v)))
            if not (np.isfinite(biggest) and np.isfinite(speed)) or biggest > limit or speed * dt > 1.0:
                if not np.isfinite(biggest) or not np.isfinite(speed):
                    quantity = "non-finite positions/velocities"
                elif biggest > limit:
                    quantity = f"a node at distance {biggest:.3g}"
                else:
                    quantity = f"a node moving {speed * dt:.3g} per step"
                raise SolverError(
                    f"faithful solver diverged at step {step} (dt {dt:.3g}): {quantity} in a model normalised to a "
                    "unit sphere; the time step is above the stability limit (use dt_rule='all_terms' or a smaller "
                    "dt_safety)"
                )
    stats.steps = max_steps
    ev = evaluate(model, x, theta, percent)
    stats.force_evaluations += 1
    stats.residual = float(np.max(np.linalg.norm(ev.forces, axis=1))) / force_scale
    stats.converged = stats.residual <= tolerance
    stats.message = (
        f"{'converged' if stats.converged else 'capped'}: residual {stats.residual:.2e} after {max_steps} steps"
    )
    return x, v, ev.theta, stats
