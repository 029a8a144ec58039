"""The fast equilibrium solver: Levenberg–Marquardt-damped Gauss–Newton on the bar-and-hinge energy.

It minimises the same energy as the faithful integrator (``core.solve.forces``) directly instead of integrating damped
dynamics towards it. Each iteration:

1. evaluates the exact forces ``F = −∇E`` and the per-element Jacobians;
2. assembles a positive semi-definite Gauss–Newton Hessian: bar blocks ``k (d̂d̂ᵀ + max(0, 1 − L0/ℓ)(I − d̂d̂ᵀ))``
   (the geometric term is kept where it is positive), ``k ∇θ ∇θᵀ`` per hinge, ``k_f ∇α ∇αᵀ`` per face corner;
3. solves ``(H + λ I) p = F`` (``λ`` is the Levenberg–Marquardt damping, which also removes the six rigid-body null
   modes) directly, with a fresh sparse factorisation (nested dissection and multifrontal Cholesky,
   ``core.solve.dissection``; the block-tridiagonal one of ``core.solve.linalg`` before it). Conjugate gradients
   preconditioned by an *earlier* factorisation did this before; once the factorisation went through LAPACK
   (``core.solve.lapack``, ~3× cheaper) the exact Gauss–Newton step won: one iteration per animation frame instead of
   two (a CG step solved to 1e-2 leaves the residual at ~1e-4), 40 → 27 ms CPU per frame at 2,048 faces;
4. accepts ``x + a p`` by an Armijo backtracking line search on the energy (θ unwrapped against the current θ),
   shrinking λ after easy steps and growing it after failures; a full step far from equilibrium is stretched (2p,
   4p) while the energy keeps falling (:data:`STRETCH`). Steps are capped to a fraction of the model size so a
   0 → 100 % jump cannot throw hinges through each other in one step.

Near convergence the energy decrease falls under floating-point resolution; there a step is accepted when it
reduces the residual force instead.
Pinned nodes (``fixed``, a boolean mask of degrees of freedom, ``core.solve.constraints``) are fixed degrees of
freedom, not stiff springs: their force is left out of the right-hand side and the residual, their step is zero,
and the factorisation gets a large diagonal there so it decouples them.
The free block is solved exactly as without pins, so pins do not change the order of convergence (quadratic with an
exact Hessian; with the Gauss–Newton one, a pin that turns a rigid motion into a soft pivot slows the tail).
"""

from __future__ import annotations

import time
from collections.abc import Generator
from dataclasses import dataclass

import numpy as np

from .. import run_to_end
from .dissection import DissectionFactor, NestedDissection
from .forces import Evaluation, evaluate, exact_hessian_blocks
from .model import BarHingeModel

MAX_STEP = 0.25
"""Largest nodal displacement of one Newton step, in normalised units (the model fits in a unit sphere)."""

PIN_DIAGONAL = 1e12
"""Diagonal added to fixed degrees of freedom in the factorisation (relative to the force scale): decouples them."""

TAIL_RESIDUAL = 1.0
"""Residual below which a solve from the flat sheet tries the exact Hessian instead of Gauss–Newton. Measured on
every fixture and example at 60 % and 100 % (iterations of the whole set: 1,083 with 1e-2, 869 with 1.0): the exact
Newton step is better as soon as the first Gauss–Newton steps have put the bars back to length."""

SLOW_RATIO = 0.7
"""Gauss–Newton counts as slow (exact Hessian tried, wherever the residual is) when the residual shrank by less than
this factor per iteration over the last :data:`SLOW_WINDOW` iterations."""

SLOW_WINDOW = 4

SADDLE_RESIDUAL = 1e-3
"""An indefinite exact Hessian at a residual below this is a saddle: step along its negative curvature."""

TRUST_RATIO = 0.25
"""Smallest ratio of the actual to the quadratic model's energy decrease for which an exact Newton step is taken."""

MINIMUM_SHIFT = 1e-7
"""Shift (of the force scale) of the factorisation that measures whether a converged state is a minimum
(:func:`inertia_shift`). It is measured at every convergence of a solve that checks: the last Newton step's own
factorisation is shifted by ``c·residual`` (up to ~1e-4 of the force scale), which hid a small negative curvature —
CircularPleat-antiFacet at 25 % once ended on a state the report then called a saddle."""

SADDLE_STEP = 0.05
"""Largest nodal displacement of a negative-curvature step out of a saddle (normalised units)."""

CURVED_ESCAPES_AFTER = 3
"""Escapes from saddles in one solve after which an escape follows the curve out of the saddle
(:func:`_escape_curvature`) instead of a straight line. The way out of a flat saddle curves: straight along the
negative-curvature direction the bars stretch by the square of the step, so the energy rose beyond 1/32 of
:data:`SADDLE_STEP` and Newton converged again one short escape further on. A CircularPleat-antiFacet with one
crease point moved 0.5 mm (a designer's edit), at 61 %, crept so along a saddle of curvature −6.6e-6 for ~200
escapes (500 iterations; its bake stopped at the cap, unconverged, at that frame); with curved escapes from the
third on, 367. From the first escape on it was 306, but the ordinary single escapes of the fixtures' paths changed
too: CircularPleat at 60 % then ended in another of its near-equal minima than its 20-frame animation. On 64 drawn
patterns at 60 % and 100 % (128 folds) only 3 folds change: 3,659 → 3,637 iterations in all."""

STRETCH = 4.0
"""Largest factor a full Gauss–Newton step is stretched by (doubling while the energy keeps falling, within
:data:`MAX_STEP`) where the residual is at least :data:`STRETCH_RESIDUAL`. Gauss–Newton does not see negative
curvature: rolling off a saddle, or down the far side of a snap-through, its steps only grew ×1.25 per iteration
(CircularPleat-antiFacet at 100 %: 131 → 112 iterations, the same states; 863 → 834 over every fixture and example
at 60 % and 100 %)."""

STRETCH_RESIDUAL = 1e-2
"""Residual below which a Gauss–Newton step is not stretched: there Gauss–Newton may be settling on a saddle, which
the minimum check, not round-off in the step, must leave (:func:`branch_chooser`) — unless it is rolling off one
(:data:`STRETCH_AFTER_ESCAPE`)."""

STRETCH_AFTER_ESCAPE = True
"""After a negative-curvature step out of a saddle, Gauss–Newton steps are stretched at any residual until the next
exact Newton step: the side was chosen by the escape (:func:`branch_chooser`), and Gauss–Newton, blind to the
negative curvature it rolls down, grew its steps only ×1.2 per iteration below :data:`STRETCH_RESIDUAL`
(CircularPleat-antiFacet at 100 %: 112 → 107 iterations, the same state; no other fixture or example changes)."""

SHIFT_FACTOR = (1e-4, 1e-2, 10.0)
"""Smallest, first and largest factor ``c`` of the exact step's damping ``c · residual`` (Levenberg–Marquardt with
damping ∝ the residual keeps quadratic convergence): divided by 10 after a full step whose energy decrease the
quadratic model predicted (≥ 3/4), multiplied by 10 after a shortened or rejected one, and when the residual
stagnates (:data:`STAGNATION_WINDOW`)."""

STAGNATION_WINDOW = 8
"""The damping factor grows when the residual of the last this-many iterations is not below half the best before:
in a nearly flat valley (a soft buckled state) small damping lets Newton steps slide along it without end."""

ROUNDOFF_RESIDUAL = 1e-4
"""Below this residual a solve that stagnates (:data:`STAGNATION_WINDOW`) measures the round-off floor of its forces
(:func:`roundoff_floor`), at most once per window."""

ROUNDOFF_FACTOR = 10.0
"""A stagnating solve whose residual is within this factor of the round-off floor is converged: no representable
position is measurably closer to equilibrium. A fuzzed 71-face sheet whose border four straight creases cross at
grazing angles (corners of 0.09°) stagnated at residual 1.4e-6 for 300 iterations, where moving the positions by
one unit in the last place changes the forces by up to 7.6e-7 (ordinary patterns: ~1e-10)."""

INDEFINITE_BACKOFF = 3
"""Iterations without an exact-Hessian attempt after one found the Hessian indefinite away from a saddle (unless
the residual halves first): far from equilibrium negative curvature persists, and each attempt costs the exact
blocks and a factorisation for nothing (the Gauss–Newton step is taken instead)."""


RESCUE_AFTER = 100
"""Iterations of one solve after which an iteration at a residual above :data:`RESCUE_RESIDUAL` that would fall
back to Gauss–Newton takes a projected-Newton step instead (:func:`_projected_step`; the rescue of crumpling
patterns). Every fixture and example converges each path stage in at most 62 iterations (CircularPleat-antiFacet 58,
Treble_Clef 62, at 60 and 100 %), so none is touched."""

RESCUE_RESIDUAL = 1.0
"""Residual above which a rescued solve (:data:`RESCUE_AFTER`) replaces the Gauss–Newton fallback."""

RESCUE_MU_MAX = 1e6
"""Largest damping (of the force scale) a rescue starts an iteration with after one whose every try was rejected
(this iteration falls back to Gauss–Newton); the rejections' own growth (2^78 after twelve) made every later try of
the solve fail, twelve factorisations each (a reviewer's forced failure: 636 factorisations, none accepted)."""

RESCUE = True
"""Whether the rescue is on at all (off: the solver as before, bit for bit)."""

RESCUE_SCALED = True
"""The rescue's damping is scaled per node by ``(ℓ_typ / ℓ_i)²``, ``ℓ_i`` the smallest moment arm of the hinges at
node ``i`` (``ℓ_typ`` their median): a wing squashed onto its hinge line turns its fold angle by ~|move| / h, so the
quadratic model holds only within ~h there, and an isotropic damping held every other node to that distance too."""

SCATTER_UNIT = 20_000
"""Node-block pairs whose scatter indices :meth:`HessianAssembler.steps` computes per unit (~15 ms)."""


class HessianAssembler:
    """Scatter indices of every element block into the storage of the sparse factorisation, computed once per model.

    ``matrix`` is the storage and factorisation, built on :meth:`coupling_pairs`: by default a
    :class:`.dissection.NestedDissection` (nested dissection, multifrontal Cholesky); a
    :class:`.linalg.BlockTridiagonal`, the level-set band it replaced, has the same interface (the benchmarks compare
    them), and tests pass other leaf sizes.
    """

    def __init__(self, model: BarHingeModel, matrix: NestedDissection | None = None):
        run_to_end(self._setup_steps(model, matrix))

    @classmethod
    def steps(cls, model: BarHingeModel, matrix: NestedDissection) -> Generator[str, None, HessianAssembler]:
        """The assembler in units for a Blender job: the scatter indices :data:`SCATTER_UNIT` block pairs at a
        time (one call took 40–130 ms at 5,000 faces); the same assembler as the constructor makes."""
        assembler = cls.__new__(cls)
        yield from assembler._setup_steps(model, matrix)
        return assembler

    def _setup_steps(self, model: BarHingeModel, matrix: NestedDissection | None) -> Generator[str, None, None]:
        self.model = model
        tri = model.triangles
        wings = model.hinge_wings
        self.matrix = NestedDissection(model.n_nodes, self.coupling_pairs(model)) if matrix is None else matrix

        def index_steps(rows: np.ndarray, cols: np.ndarray) -> Generator[str, None, np.ndarray]:
            parts = []
            for start in range(0, len(rows), SCATTER_UNIT):
                parts.append(
                    self.matrix.scatter_index(rows[start : start + SCATTER_UNIT], cols[start : start + SCATTER_UNIT])
                )
                yield "scatter"
            return np.concatenate(parts) if parts else np.zeros((0, 3, 3), dtype=np.int64)

        i, j = model.bar_nodes[:, 0], model.bar_nodes[:, 1]
        self.bar_index = yield from index_steps(np.concatenate([i, j, i, j]), np.concatenate([i, j, j, i]))
        hn = np.column_stack([wings, model.hinge_edge_nodes])  # (h, 4): w1, w2, v1, v2
        hinge_index = yield from index_steps(np.repeat(hn, 4, axis=1).reshape(-1), np.tile(hn, (1, 4)).reshape(-1))
        self.hinge_index = hinge_index.reshape(len(hn), 4, 4, 3, 3)
        face_index = yield from index_steps(np.repeat(tri, 3, axis=1).reshape(-1), np.tile(tri, (1, 3)).reshape(-1))
        self.face_index = face_index.reshape(len(tri), 3, 3, 3, 3)
        self.assemblies = 0
        # one scatter index for bars, hinges and faces (hinge and face blocks [e, a, i, b, j]) and the value vector it
        # reads, with its hinge and face parts as (e, 12, 12) / (e, 9, 9) views written in place by both assemblies;
        # exact_hessian_blocks keeps its scratch arrays in the same dict
        nb, nh, nf = len(model.bar_k), len(model.hinge_k), len(tri)
        index = [self.bar_index.reshape(-1), self.hinge_index.transpose(0, 1, 3, 2, 4).reshape(-1)]
        index.append(self.face_index.transpose(0, 1, 3, 2, 4).reshape(-1))
        values = np.zeros(sum(len(i) for i in index))
        self.work: dict[str, np.ndarray] = {
            "index": np.concatenate(index),
            "values": values,
            "hinge out": values[36 * nb : 36 * nb + 144 * nh].reshape(nh, 12, 12),
            "face out": values[36 * nb + 144 * nh :].reshape(nf, 9, 9),
        }

    @staticmethod
    def coupling_pairs(model: BarHingeModel) -> np.ndarray:
        """Node pairs the Hessian couples: bars, triangle sides and each hinge's two wing nodes."""
        tri = model.triangles
        return np.concatenate([model.bar_nodes, tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [0, 2]], model.hinge_wings])

    def _bars_into(self, values: np.ndarray, bars: np.ndarray) -> None:
        """Bar blocks ``K`` as the four node blocks ``K, K, −K, −K`` (ii, jj, ij, ji) at the head of ``values``."""
        nb = len(bars)
        per_bar = values[: 36 * nb].reshape(4, nb, 3, 3)
        per_bar[0], per_bar[1] = bars, bars
        np.negative(bars, out=per_bar[2])
        per_bar[3] = per_bar[2]

    def assemble(self, ev: Evaluation) -> np.ndarray:
        """Gauss–Newton Hessian storage from an evaluation made with ``jacobians=True``: bar blocks, ``k ∇θ∇θᵀ``
        per hinge and ``k_f Σ ∇α∇αᵀ`` per face, each a batched outer product written into the kept value vector
        (``self.work``)."""
        work = self.work
        values = work["values"]
        self._bars_into(values, ev.bar_blocks)
        if ev.hinge_grad is not None and len(ev.hinge_k):
            g = ev.hinge_grad.reshape(len(ev.hinge_k), 12)
            np.multiply(g[:, :, None], (ev.hinge_k[:, None] * g)[:, None, :], out=work["hinge out"])
            if ev.hinge_fading is not None and len(ev.hinge_fading):
                work["hinge out"][ev.hinge_fading] += ev.hinge_fading_gn
        else:
            work["hinge out"].fill(0.0)
        if ev.face_grad is not None:
            fg = ev.face_grad.reshape(len(ev.face_grad), 3, 9)
            np.matmul(fg.transpose(0, 2, 1), fg, out=work["face out"])
            work["face out"] *= self.model.face_k
        else:
            work["face out"].fill(0.0)
        self.assemblies += 1
        return self.matrix.assemble(work["index"], values)

    def assemble_exact(self, x: np.ndarray, ev: Evaluation) -> np.ndarray:
        """Exact Hessian storage (``forces.exact_hessian_blocks``) at ``x``; ``ev`` made with ``jacobians=True``.

        The element blocks are scattered in the order they are computed in (hinges and faces ``[e, a, i, b, j]``,
        no transposing copy). The scatter index (bars, hinges, faces concatenated) and the scratch arrays are made
        on the first call and kept; the hinge and face blocks are computed straight into the kept value vector.
        """
        work = self.work
        values = work["values"]
        bars, hinges, faces = exact_hessian_blocks(self.model, x, ev, work)
        self._bars_into(values, bars)
        for blocks, part in ((hinges, work["hinge out"]), (faces, work["face out"])):
            if blocks is None:
                part.fill(0.0)
            elif not np.may_share_memory(blocks, part):  # not computed in place (e.g. shapes changed)
                part[...] = blocks.transpose(0, 1, 3, 2, 4).reshape(part.shape)
        self.assemblies += 1
        return self.matrix.assemble(work["index"], values)


@dataclass
class NewtonStats:
    """Counters of one Newton run (honest accounting for the benchmark)."""

    iterations: int = 0
    force_evaluations: int = 0
    energy_evaluations: int = 0
    hessian_assemblies: int = 0
    linear_solves: int = 0
    converged: bool = False
    residual: float = float("inf")
    message: str = ""
    exact_iterations: int = 0
    saddle_escapes: int = 0
    negative_pivots: int | None = None
    stretched_steps: int = 0
    rescue_steps: int = 0
    shift_factor: float = SHIFT_FACTOR[1]
    """The current factor of the exact step's damping (see :data:`SHIFT_FACTOR`)."""

    def damp_more(self) -> None:
        """Ten times the exact step's damping factor, at most :data:`SHIFT_FACTOR`'s largest."""
        self.shift_factor = min(self.shift_factor * 10.0, SHIFT_FACTOR[2])

    def damp_less(self) -> None:
        """A tenth of the exact step's damping factor, at least :data:`SHIFT_FACTOR`'s smallest."""
        self.shift_factor = max(self.shift_factor * 0.1, SHIFT_FACTOR[0])


@dataclass
class NewtonProgress:
    """What one Newton iteration leaves behind (yielded by :func:`newton_steps`, e.g. for a progress bar)."""

    iteration: int
    residual: float
    x: np.ndarray
    theta: np.ndarray


@dataclass
class Fixed:
    """Pinned degrees of freedom of one solve: ``free`` ``(n, 3)`` bool (``None``: nothing pinned) and the diagonal
    ``diag`` (``3n``) that decouples the pinned ones in a factorisation."""

    free: np.ndarray | None = None
    diag: np.ndarray | None = None

    @classmethod
    def of(cls, fixed: np.ndarray | None, force_scale: float) -> Fixed:
        if fixed is None or not np.any(fixed):
            return cls()
        free = ~np.asarray(fixed, dtype=bool).reshape(-1, 3)
        return cls(free, (~free).reshape(-1).astype(np.float64) * PIN_DIAGONAL * force_scale)

    def forces(self, f: np.ndarray) -> np.ndarray:
        """Forces on the free degrees of freedom only (``(n, 3)`` or flat ``3n``)."""
        if self.free is None:
            return f
        return f * (self.free if f.ndim == 2 else self.free.reshape(-1))

    def shift(self, shift: float) -> float | np.ndarray:
        """A factorisation shift with the pinned degrees of freedom decoupled."""
        return shift if self.diag is None else shift + self.diag


def newton_solve(
    model: BarHingeModel,
    x0: np.ndarray,
    theta0: np.ndarray,
    percent: float,
    **options,
) -> tuple[np.ndarray, np.ndarray, Evaluation, NewtonStats, float]:
    """Minimise the energy from ``x0`` (normalised) with fold-angle history ``theta0`` to the end (see
    :func:`newton_steps` for the options). Returns ``(x, theta, evaluation at x, stats, final λ)``."""
    return run_to_end(newton_steps(model, x0, theta0, percent, **options))


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
    exact_tail: bool = True,
    check_minimum: bool = True,
    tail_residual: float = TAIL_RESIDUAL,
) -> Generator[NewtonProgress, None, tuple[np.ndarray, np.ndarray, Evaluation, NewtonStats, float]]:
    """Minimise the energy from ``x0`` (normalised) with fold-angle history ``theta0``, one iteration per ``next``.

    Yields a :class:`NewtonProgress` after every accepted iteration, so a caller can work in slices (Blender's modal
    jobs) and stop between any two; the generator's return value (``StopIteration.value``) is
    ``(x, theta, evaluation at x, stats, final λ)``. The residual is ``max_i |F_i| / force_scale``.

    ``fixed`` (``(n, 3)`` bool): pinned degrees of freedom; they keep their value in ``x0`` and their (reaction)
    forces are left out of the residual.

    Far from equilibrium every iteration is Gauss–Newton. Once the residual is below ``tail_residual``, or
    Gauss–Newton is slow (:data:`SLOW_RATIO`), an iteration first tries the exact Hessian (``exact_tail``): where it
    is positive definite (no negative pivot) its Newton step converges quadratically; where it is indefinite and the
    residual is below :data:`SADDLE_RESIDUAL` the state is a saddle and a step along the negative-curvature
    direction of the factorisation leaves it; otherwise (indefinite far from equilibrium, or a rejected step) the
    iteration falls back to the PSD Gauss–Newton matrix. With ``check_minimum`` a converged state is accepted only
    as a minimum: its inertia is measured (one factorisation at :data:`MINIMUM_SHIFT`, as the solver reports it) and
    a saddle is left along its negative curvature (warm-started animation frames skip it).
    """
    assembler = assembler or HessianAssembler(model)
    stats = NewtonStats()
    t_start = time.perf_counter()
    x = np.array(x0, dtype=np.float64)
    ev = evaluate(model, x, theta0, percent, jacobians=True)
    stats.force_evaluations += 1
    fx = Fixed.of(fixed, force_scale)
    lam = float(lm_lambda) * force_scale
    lam_min = 1e-9 * force_scale
    history: list[float] = []
    indefinite_at: tuple[int, float] | None = None  # (iteration, residual) of the last indefinite exact Hessian
    rolling_off = False  # a saddle was left and no exact Newton step taken since (STRETCH_AFTER_ESCAPE)
    floor_checked_at = -STAGNATION_WINDOW  # the iteration the round-off floor was last measured at
    rescue_mu: float | None = None  # damping of the projected-Newton rescue (None: not rescuing)
    for it in range(max_iterations + 1):
        residual = float(np.max(np.linalg.norm(fx.forces(ev.forces), axis=1))) / force_scale
        stats.residual = residual
        history.append(residual)
        if not np.isfinite(residual):
            stats.message = f"non-finite residual force at Newton iteration {it}"
            break
        step = None
        stagnating = len(history) > STAGNATION_WINDOW and min(history[-STAGNATION_WINDOW:]) > 0.5 * min(
            history[:-STAGNATION_WINDOW]
        )
        floor = None
        if (
            residual > tolerance
            and stagnating
            and residual <= ROUNDOFF_RESIDUAL
            and floor_checked_at <= it - STAGNATION_WINDOW
        ):
            floor, floor_checked_at = roundoff_floor(model, x, ev, percent, force_scale, stats, fx), it
        at_floor = floor is not None and residual <= ROUNDOFF_FACTOR * floor
        if residual <= tolerance or at_floor:
            if exact_tail and check_minimum and it < max_iterations:
                # converged, but to a minimum? (a Gauss–Newton run can settle on a saddle: it never sees the
                # negative curvature; a Newton step's factorisation is shifted by ~c·residual, which can hide a
                # small one). Measured at MINIMUM_SHIFT; at a saddle, step out along it and go on.
                step = _leave_saddle(model, assembler, x, ev, force_scale, percent, stats, fx)
            if step is None:
                stats.converged = True
                stats.message = f"converged: residual {residual:.2e} ≤ {tolerance:.1e} after {it} iterations"
                if at_floor:
                    stats.message = (
                        f"converged to round-off: residual {residual:.2e} (a move of the positions by one unit in "
                        f"the last place changes it by {floor:.1e}) after {it} iterations"
                    )
                break
        elif it == max_iterations:
            stats.message = f"not converged: residual {residual:.2e} after {it} iterations (limit)"
            break
        elif time_limit is not None and time.perf_counter() - t_start > time_limit:
            stats.message = f"not converged: residual {residual:.2e} after {it} iterations (time limit {time_limit}s)"
            break
        stats.iterations = it + 1
        rhs = fx.forces(ev.forces).reshape(-1)
        slow = len(history) > SLOW_WINDOW and residual > history[-1 - SLOW_WINDOW] * SLOW_RATIO**SLOW_WINDOW
        if stagnating:
            stats.damp_more()
        backing_off = indefinite_at is not None and (
            it < indefinite_at[0] + INDEFINITE_BACKOFF and residual > 0.5 * indefinite_at[1]
        )
        if step is None and exact_tail and (residual <= tail_residual or slow) and not backing_off:
            step = _exact_step(model, assembler, x, ev, rhs, residual, lam, force_scale, percent, stats, fx)
            if step is None and stats.negative_pivots:
                indefinite_at = (it, residual)
        if step is None and RESCUE and residual > RESCUE_RESIDUAL and (rescue_mu is not None or it >= RESCUE_AFTER):
            before = 1e-3 if rescue_mu is None else rescue_mu
            step, rescue_mu = _projected_step(model, assembler, x, ev, rhs, before, force_scale, percent, stats, fx)
            if step is None:  # all rejected: damp the next try more, not by the 2^78 the rejections reached
                rescue_mu = min(10.0 * before, RESCUE_MU_MAX)
        if step is not None:
            trial, tev, kind = step
            accepted = True
            rolling_off = kind == "saddle" and STRETCH_AFTER_ESCAPE
            if kind == "saddle":
                history.clear()  # a new basin: judge Gauss–Newton afresh
                lam = max(lam, float(lm_lambda) * force_scale)
            else:
                lam = max(lam * 0.3, lam_min)
        else:
            trial, tev, accepted, lam = _gauss_newton_step(
                model, assembler, x, ev, rhs, residual, lam, lam_min, force_scale, percent, stats, fx, rolling_off
            )
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
            it + 1, float(np.max(np.linalg.norm(fx.forces(ev.forces), axis=1))) / force_scale, x, ev.theta
        )
    if stats.rescue_steps:
        stats.message += f" ({stats.rescue_steps} projected-Newton rescue steps)"
    return x, ev.theta, ev, stats, lam / force_scale


def _node_scale(model: BarHingeModel, x: np.ndarray) -> np.ndarray:
    """Per-degree-of-freedom damping weights ``(ℓ_typ / ℓ_i)²`` (``3n``, ≥ 1) of the rescue (:data:`RESCUE_SCALED`):
    ``ℓ_i`` the smallest moment arm of the hinges node ``i`` belongs to (wing or edge node), ``ℓ_typ`` the median
    over the hinges."""
    n = model.n_nodes
    scale = np.ones(n)
    if not len(model.hinge_k):
        return np.repeat(scale, 3)
    wings, edge = model.hinge_wings, model.hinge_edge_nodes
    a, b = x[edge[:, 0]], x[edge[:, 1]]
    e = b - a
    e /= np.maximum(np.linalg.norm(e, axis=1), 1e-300)[:, None]
    arm = np.minimum(
        np.linalg.norm(np.cross(x[wings[:, 0]] - a, e), axis=1), np.linalg.norm(np.cross(x[wings[:, 1]] - a, e), axis=1)
    )
    typical = float(np.median(arm))
    arm = np.clip(arm, 1e-6 * typical, typical)
    ell = np.full(n, typical)
    for nodes in (wings[:, 0], wings[:, 1], edge[:, 0], edge[:, 1]):
        np.minimum.at(ell, nodes, arm)
    return np.repeat((typical / ell) ** 2, 3)


def _translation_complement(nodes: int) -> np.ndarray:
    """``(3·nodes, 3·nodes − 3)``: an orthonormal basis of the motions of ``nodes`` nodes (rows node-major) that
    move their centroid by nothing, i.e. orthogonal to the three translations."""
    t = np.tile(np.eye(3), (nodes, 1)) / np.sqrt(nodes)
    q, _ = np.linalg.qr(np.hstack([t, np.eye(3 * nodes)]))
    return np.ascontiguousarray(q[:, 3:])


_COMPLEMENTS: dict[int, np.ndarray] = {}


def _psd_part(blocks: np.ndarray) -> None:
    """Each symmetric block of ``blocks`` ``(e, q, q)`` (an element's Hessian over its ``q / 3`` nodes, which no
    translation changes) replaced in place by its positive semidefinite part: projected onto the complement of the
    translations (``q − 3`` unknowns, half the ``eigh`` cost of the full block), batched ``eigh``, negative
    eigenvalues set to zero, and back."""
    if not len(blocks):
        return
    q = blocks.shape[1]
    Q = _COMPLEMENTS.get(q)
    if Q is None:
        Q = _COMPLEMENTS[q] = _translation_complement(q // 3)
    reduced = Q.T @ blocks @ Q
    reduced += reduced.transpose(0, 2, 1)
    reduced *= 0.5
    w, v = np.linalg.eigh(reduced)
    np.maximum(w, 0.0, out=w)
    u = Q @ v  # (e, q, q − 3)
    np.matmul(u * w[:, None, :], u.transpose(0, 2, 1), out=blocks)


def _projected_step(
    model: BarHingeModel,
    assembler: HessianAssembler,
    x: np.ndarray,
    ev: Evaluation,
    rhs: np.ndarray,
    mu: float,
    force_scale: float,
    percent: float,
    stats: NewtonStats,
    fx: Fixed,
) -> tuple[tuple[np.ndarray, Evaluation, str] | None, float]:
    """Projected Newton with Levenberg–Marquardt damping ``mu`` (of the force scale) adapted by the ratio of the
    actual to the predicted energy decrease: each element's exact Hessian block is replaced by its positive
    semidefinite part, assembled and factored with shift ``mu`` (always positive definite). Returns the step (or
    ``None``) and the next ``mu``."""
    n = model.n_nodes
    work = assembler.work
    values = work["values"]
    _, hinges, faces = exact_hessian_blocks(model, x, ev, work)
    assembler._bars_into(values, ev.bar_blocks)  # bars: the geometric term clamped at 0 is their PSD part
    for blocks, part in ((hinges, work["hinge out"]), (faces, work["face out"])):
        if blocks is None:
            part.fill(0.0)
        else:
            if not np.may_share_memory(blocks, part):
                part[...] = blocks.transpose(0, 1, 3, 2, 4).reshape(part.shape)
            _psd_part(part)
    H = assembler.matrix.assemble(work["index"], values)
    stats.hessian_assemblies += 1
    scale = _node_scale(model, x) if RESCUE_SCALED else 1.0
    growth = 2.0  # Nielsen's rule: a rejected step multiplies mu by 2, 4, 8, … (2^78 after 12 rejections)
    for _attempt in range(12):
        shift = mu * force_scale * scale
        try:
            factor = assembler.matrix.factor(H, fx.shift(shift))
        except np.linalg.LinAlgError:
            mu, growth = mu * growth, 2.0 * growth
            continue
        stats.linear_solves += 1
        p = fx.forces(factor.apply(rhs)).reshape(n, 3)
        if not np.all(np.isfinite(p)):
            mu, growth = mu * growth, 2.0 * growth
            continue
        slope = float(np.dot(rhs, p.reshape(-1)))
        curvature = slope - float(np.sum(shift * (p * p).reshape(-1)))  # pᵀH̃p
        biggest = float(np.max(np.linalg.norm(p, axis=1)))
        if biggest > MAX_STEP:
            c = MAX_STEP / biggest
            p *= c
            slope, curvature = c * slope, c * c * curvature
        predicted = slope - 0.5 * curvature
        if slope <= 0 or predicted <= 0:
            mu, growth = mu * growth, 2.0 * growth
            continue
        trial = x + p
        tev = evaluate(model, trial, ev.theta, percent, jacobians=True)
        stats.force_evaluations += 1
        rho = (ev.energy - tev.energy) / predicted
        if rho > TRUST_RATIO:
            mu = max(mu * max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3), 1e-9)
            stats.rescue_steps += 1
            return (trial, tev, "projected"), mu
        mu *= growth
        growth *= 2.0
    return None, mu


def roundoff_floor(
    model: BarHingeModel,
    x: np.ndarray,
    ev: Evaluation,
    percent: float,
    force_scale: float,
    stats: NewtonStats,
    fx: Fixed,
) -> float:
    """The residual's round-off floor at ``x``: the largest change of the (free) forces, over the force scale, when
    every coordinate moves by one unit in the last place of the model's size (two fixed random moves, the same on
    every machine). Slivers forced by the drawn creases (corners of a tenth of a degree) make the hinge and
    face-angle forces so steep that this reaches 1e-7: no Newton step can then place the nodes closer to equilibrium
    than a few times it."""
    ulp = np.finfo(np.float64).eps * max(float(np.max(np.abs(x))), 1e-300)
    moves = np.random.default_rng(20261125).standard_normal((2, *x.shape))
    worst = 0.0
    for move in moves:
        moved = evaluate(model, x + ulp * move, ev.theta, percent)
        stats.force_evaluations += 1
        change = fx.forces(moved.forces - ev.forces)
        worst = max(worst, float(np.max(np.linalg.norm(change, axis=1))) / force_scale)
    return worst


def _exact_step(
    model: BarHingeModel,
    assembler: HessianAssembler,
    x: np.ndarray,
    ev: Evaluation,
    rhs: np.ndarray,
    residual: float,
    lam: float,
    force_scale: float,
    percent: float,
    stats: NewtonStats,
    fx: Fixed,
) -> tuple[np.ndarray, Evaluation, str] | None:
    """One exact-Hessian iteration: a Newton step where ``∇²E`` is positive definite, a negative-curvature step at a
    saddle; ``None`` when neither is accepted (the caller takes a Gauss–Newton step instead).

    The shift is ``λ + c·residual`` (Levenberg–Marquardt with damping ∝ the residual keeps quadratic convergence;
    ``c`` adapts, :data:`SHIFT_FACTOR`) plus what lifts the rigid rotations (:func:`rigid_shift`).
    """
    n = model.n_nodes
    H = assembler.assemble_exact(x, ev)
    stats.hessian_assemblies += 1
    shift = _exact_shift(x, ev, residual, lam, force_scale, stats, fx)
    try:  # away from a saddle an indefinite factorisation is of no use: stop at its first negative pivot
        factor = assembler.matrix.factor(H, fx.shift(shift), inertia=True, definite_only=residual > SADDLE_RESIDUAL)
    except np.linalg.LinAlgError:
        return None
    stats.linear_solves += 1
    stats.negative_pivots = factor.negative_pivots
    if factor.negative_pivots == 0:
        p = fx.forces(factor.apply(rhs)).reshape(n, 3)
        if not np.all(np.isfinite(p)):
            return None
        slope = float(np.dot(rhs, p.reshape(-1)))
        curvature = slope - shift * float(np.sum(p * p))  # pᵀ∇²E p, since (∇²E + shift) p = F
        biggest = float(np.max(np.linalg.norm(p, axis=1)))
        if biggest > MAX_STEP:
            c = MAX_STEP / biggest
            p *= c
            slope, curvature = c * slope, c * c * curvature
        if slope <= 0:
            return None
        q = _geodesic_acceleration(model, factor, x, ev, p, percent, stats, fx)
        a = 1.0
        for _ls in range(6):
            trial = x + a * p + (0.5 * a * a) * q
            full = _ls == 0
            tev = evaluate(model, trial, ev.theta, percent, forces=full, jacobians=full)
            stats.force_evaluations += int(full)
            stats.energy_evaluations += int(not full)
            decrease = ev.energy - tev.energy
            predicted = a * slope - 0.5 * a * a * curvature
            # trust the quadratic model only where it predicts the decrease (trust-region ratio ≥ ¼): a step far
            # along a soft mode, where the energy is not quadratic, is shortened instead of zig-zagging
            if decrease >= TRUST_RATIO * predicted or _residual_judges(
                model, trial, tev, ev, residual, force_scale, percent, stats, fx
            ):
                stats.exact_iterations += 1
                if a == 1.0 and decrease >= 0.75 * predicted:
                    stats.damp_less()
                elif a < 1.0:
                    stats.damp_more()
                return trial, tev, "newton"
            a *= 0.5
        stats.damp_more()
        return None
    if residual > SADDLE_RESIDUAL:
        return None
    return _saddle_step(model, factor, x, ev, percent, stats, fx)


def _exact_shift(
    x: np.ndarray, ev: Evaluation, residual: float, lam: float, force_scale: float, stats: NewtonStats, fx: Fixed
) -> float:
    """Diagonal shift of an exact-Hessian factorisation: ``λ + c·residual`` (``c`` = ``stats.shift_factor``) plus
    the lift of the rigid rotations (:func:`rigid_shift`)."""
    return lam + stats.shift_factor * residual * force_scale + rigid_shift(x, ev.forces, fx)


def rigid_shift(x: np.ndarray, forces: np.ndarray, fx: Fixed | None = None) -> float:
    """Diagonal shift that makes the exact Hessian positive on the rigid rotations of the nodes at ``x``.

    The energy is invariant under rotation, so along the straight path ``x + t u`` with ``u = ω × r`` its curvature
    is ``uᵀ∇²E u = F · (ω × (ω × r))`` (``F = −∇E``): zero at equilibrium, of either sign away from it. The
    most negative of these (the lowest generalised eigenvalue of ``M_kl = F · ½(e_k × (e_l × r) + e_l × (e_k × r))``
    against the rotations' Gram matrix) is what a shift must exceed; twice it is returned. Translations have zero
    curvature everywhere and are lifted by any positive shift. (A shift of ``10 · residual`` did this before, and
    damped the soft modes of the sheet ten times more than needed: 49 → 26 iterations on Carved_Cylinder at 100 %.)
    With pins (``fx.free``) the rotations are held, and nothing is added.
    """
    if fx is not None and fx.free is not None:
        return 0.0
    r = x - x.mean(axis=0)
    eye = np.eye(3)
    u = np.stack([np.cross(eye[k], r) for k in range(3)])  # (3, n, 3)
    gram = np.einsum("kni,lni->kl", u, u)
    m = np.einsum("ni,klni->kl", forces, np.cross(eye[:, None, None, :], np.cross(eye[None, :, None, :], r)))
    m = 0.5 * (m + m.T)
    try:
        c = np.linalg.cholesky(gram)
    except np.linalg.LinAlgError:  # all nodes on one line: a rotation about it is not a motion
        return 0.0
    ci = np.linalg.inv(c)
    lowest = float(np.linalg.eigvalsh(ci @ m @ ci.T)[0])
    return 2.0 * max(0.0, -lowest)


def _leave_saddle(
    model: BarHingeModel,
    assembler: HessianAssembler,
    x: np.ndarray,
    ev: Evaluation,
    force_scale: float,
    percent: float,
    stats: NewtonStats,
    fx: Fixed,
) -> tuple[np.ndarray, Evaluation, str] | None:
    """At a converged state: the inertia of the exact Hessian shifted by :func:`inertia_shift` (as the solver
    reports it); a negative-curvature step if it is a saddle."""
    H = assembler.assemble_exact(x, ev)
    stats.hessian_assemblies += 1
    try:
        factor = assembler.matrix.factor(H, fx.shift(inertia_shift(x, ev.forces, force_scale, fx)), inertia=True)
    except np.linalg.LinAlgError:
        return None
    stats.negative_pivots = factor.negative_pivots
    if not factor.negative_pivots:
        return None
    return _saddle_step(model, factor, x, ev, percent, stats, fx)


def inertia_shift(x: np.ndarray, forces: np.ndarray, force_scale: float, fx: Fixed | None = None) -> float:
    """Diagonal shift of the factorisation that tells a stable minimum from a saddle at a converged state:
    :data:`MINIMUM_SHIFT` of the force scale (lifts the translations) plus :func:`rigid_shift` (the rotations)."""
    return MINIMUM_SHIFT * force_scale + rigid_shift(x, forces, fx)


def _saddle_step(
    model: BarHingeModel,
    factor: DissectionFactor,
    x: np.ndarray,
    ev: Evaluation,
    percent: float,
    stats: NewtonStats,
    fx: Fixed,
) -> tuple[np.ndarray, Evaluation, str] | None:
    """Step out of a saddle along all its unstable modes at once: ``w = L⁻ᵀ z`` with ``z`` every negative eigenvector
    of the factorisation's pivots (``DissectionFactor.negative_subspace_direction``), each mode's side and the whole
    step's side picked by :func:`branch_chooser`, the other side tried if it does not descend; up to
    :data:`SADDLE_STEP` per node, halved until the energy falls; ``None`` if it does not.

    Leaving along the one lowest pivot's eigenvector left the other unstable modes for later: Gauss–Newton (blind to
    negative curvature) settled on the next saddle, and a pleat with 20 negative directions passed a cascade of
    them (CircularPleat-antiFacet at 100 %: 163 → 131 iterations, at 60 % 92 → 78; no other fixture meets a saddle).
    """
    n = model.n_nodes
    w = factor.negative_subspace_direction(branch_chooser(n))
    if w is None:
        return None
    w = fx.forces(w.reshape(n, 3))
    if not np.any(w):
        return None
    w *= SADDLE_STEP / max(float(np.max(np.linalg.norm(w, axis=1))), 1e-300)
    if float(np.dot(branch_chooser(n), w.reshape(-1))) < 0:
        w = -w
    q = np.zeros_like(w)
    if stats.saddle_escapes >= CURVED_ESCAPES_AFTER:
        q = _escape_curvature(model, factor, x, ev.theta, w, percent, stats, fx)
    for sign in (1.0, -1.0):
        a = 1.0
        for _ls in range(8):
            trial = x + sign * a * w + (0.5 * a * a) * q
            tev = evaluate(model, trial, ev.theta, percent, forces=False)
            stats.energy_evaluations += 1
            if tev.energy < ev.energy - 1e-12 * abs(ev.energy):
                stats.saddle_escapes += 1
                return trial, tev, "saddle"
            a *= 0.5
    return None


def _escape_curvature(
    model: BarHingeModel,
    factor: DissectionFactor,
    x: np.ndarray,
    theta: np.ndarray,
    w: np.ndarray,
    percent: float,
    stats: NewtonStats,
    fx: Fixed,
) -> np.ndarray:
    """Second-order correction ``q`` of an escape ``w`` out of a saddle (:data:`CURVED_ESCAPES_AFTER`): the step
    becomes ``x ± a w + ½ a² q``, as a Newton step gets its geodesic acceleration (:func:`_geodesic_acceleration`).
    ``q`` solves the saddle's factorisation against ``d²F/dt²`` along ``w`` (central differences about a fresh
    evaluation at ``x``, so round-off in the caller's forces cannot choose it), its part along ``w`` removed: even
    in ``w``, the same on both sides. Zero when not small beside ``w``."""
    f0 = evaluate(model, x, theta, percent).forces
    stats.force_evaluations += 1
    return _curve_correction(model, factor, x, theta, f0, w, percent, stats, fx, across=True)


def _curve_correction(
    model: BarHingeModel,
    factor: DissectionFactor,
    x: np.ndarray,
    theta: np.ndarray,
    f0: np.ndarray,
    d: np.ndarray,
    percent: float,
    stats: NewtonStats,
    fx: Fixed,
    *,
    across: bool = False,
) -> np.ndarray:
    """``q`` solving ``factor`` against ``d²F/dt²`` along the direction ``d`` (central differences, ``t = ±0.1``,
    about the forces ``f0`` at ``x``): the second-order term of the curve ``x + a d + ½ a² q`` that
    :func:`_geodesic_acceleration` and :func:`_escape_curvature` step along. ``across``: its part along ``d``
    removed. Zero when not finite or not small beside ``d`` (``|q| > |d|``)."""
    h = 0.1
    fp = evaluate(model, x + h * d, theta, percent).forces
    fm = evaluate(model, x - h * d, theta, percent).forces
    stats.force_evaluations += 2
    q = fx.forces(factor.apply(fx.forces((fp - 2.0 * f0 + fm) / (h * h)).reshape(-1))).reshape(d.shape)
    stats.linear_solves += 1
    if across:
        q -= (float(np.sum(q * d)) / float(np.sum(d * d))) * d
    if not np.all(np.isfinite(q)) or np.linalg.norm(q) > np.linalg.norm(d):
        return np.zeros_like(d)
    return q


def branch_chooser(n_nodes: int) -> np.ndarray:
    """A fixed vector (``3 n_nodes``, the same on every machine) whose sign against a negative-curvature direction
    picks the side a saddle is left on.

    At a symmetric saddle (a pattern that buckles) the two sides lead to mirror or rotated branches, and the
    gradient, ~0 there, cannot choose: "downhill" was decided by round-off and by the sign LAPACK gives an
    eigenvector, which can differ between machines and numpy versions. With a fixed chooser the side is a function
    of the state alone, the same on every machine; the energy test of :func:`_saddle_step` still tries the other
    side when this one does not descend.
    """
    k = np.arange(3 * n_nodes, dtype=np.float64)
    return np.cos(k * 2.399963229728653 + 0.5) + 1e-3  # golden-angle phases: no structure a mesh can align with


def _geodesic_acceleration(
    model: BarHingeModel,
    factor: DissectionFactor,
    x: np.ndarray,
    ev: Evaluation,
    p: np.ndarray,
    percent: float,
    stats: NewtonStats,
    fx: Fixed,
) -> np.ndarray:
    """Second-order correction ``q`` of a Newton step ``p``: the step becomes the curve ``x + a p + ½ a² q``.

    Along a soft mode (a flap turning about its creases) the valley of the energy is curved: a straight step along
    its tangent climbs the stiff bars by the square of its length, the trust-region test shortens it, and the next
    iteration only comes back to the valley floor (a zig-zag of two iterations per small advance). ``q`` solves
    ``∇²E q = d²F/dt²`` along ``p`` (central differences, ``t = ±0.1``, with the same factorisation), so that
    ``∇E(x + p + ½q)`` vanishes to second order: the geodesic acceleration of Transtrum & Sethna (2012). Dropped
    (zero) when it is not small beside the step (``|q| > |p|``)."""
    return _curve_correction(model, factor, x, ev.theta, ev.forces, p, percent, stats, fx)


def _residual_judges(
    model: BarHingeModel,
    trial: np.ndarray,
    tev: Evaluation,
    ev: Evaluation,
    residual: float,
    force_scale: float,
    percent: float,
    stats: NewtonStats,
    fx: Fixed,
) -> bool:
    """Near convergence the energy decrease falls under round-off: accept a step that reduces the residual force."""
    if abs(ev.energy - tev.energy) > 1e-13 * max(abs(ev.energy), 1e-300) + 1e-300:
        return False
    rev = tev if tev.forces is not None else evaluate(model, trial, ev.theta, percent, jacobians=False)
    stats.force_evaluations += int(tev.forces is None)
    return bool(np.max(np.linalg.norm(fx.forces(rev.forces), axis=1)) < residual * force_scale)


def _gauss_newton_step(
    model: BarHingeModel,
    assembler: HessianAssembler,
    x: np.ndarray,
    ev: Evaluation,
    rhs: np.ndarray,
    residual: float,
    lam: float,
    lam_min: float,
    force_scale: float,
    percent: float,
    stats: NewtonStats,
    fx: Fixed,
    rolling_off: bool = False,
) -> tuple[np.ndarray, Evaluation, bool, float]:
    """One Levenberg–Marquardt Gauss–Newton iteration with Armijo backtracking; returns ``(x, ev, accepted, λ)``.

    A full step is stretched (:func:`_stretch`) at residuals from :data:`STRETCH_RESIDUAL`, or at any residual
    while ``rolling_off`` a saddle just left (:data:`STRETCH_AFTER_ESCAPE`)."""
    trial, tev = x, ev
    for _attempt in range(12):
        try:
            p = _step(assembler, ev, rhs, lam, stats, fx.diag).reshape(-1, 3)
        except np.linalg.LinAlgError:
            lam *= 10.0
            continue
        if not np.all(np.isfinite(p)):
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
            if decrease >= 1e-4 * a * slope or _residual_judges(
                model, trial, tev, ev, residual, force_scale, percent, stats, fx
            ):
                if a == 1.0 and decrease > 0 and (residual >= STRETCH_RESIDUAL or rolling_off):
                    trial, tev = _stretch(model, x, p, slope, trial, tev, ev, percent, stats)
                lam = max(lam * (0.3 if a == 1.0 else 1.0), lam_min)
                if a < 0.25:
                    lam *= 4.0
                return trial, tev, True, lam
            a *= 0.5
        lam *= 10.0
    return trial, tev, False, lam


def _stretch(
    model: BarHingeModel,
    x: np.ndarray,
    p: np.ndarray,
    slope: float,
    trial: np.ndarray,
    tev: Evaluation,
    ev: Evaluation,
    percent: float,
    stats: NewtonStats,
) -> tuple[np.ndarray, Evaluation]:
    """A full Gauss–Newton step ``x + p`` (at ``trial``, ``tev``) stretched to ``x + 2p``, ``x + 4p`` … while the
    energy keeps falling (Armijo against ``slope``), at most :data:`STRETCH` times and :data:`MAX_STEP` per node."""
    factor, biggest = 1.0, float(np.max(np.linalg.norm(p, axis=1)))
    while 2.0 * factor <= STRETCH and 2.0 * factor * biggest <= MAX_STEP:
        farther = x + (2.0 * factor) * p
        fev = evaluate(model, farther, ev.theta, percent, forces=False)
        stats.energy_evaluations += 1
        if fev.energy >= tev.energy or ev.energy - fev.energy < 1e-4 * 2.0 * factor * slope:
            break
        trial, tev, factor = farther, fev, 2.0 * factor
    if factor > 1.0:
        stats.stretched_steps += 1
    return trial, tev


def _step(
    assembler: HessianAssembler,
    ev: Evaluation,
    rhs: np.ndarray,
    lam: float,
    stats: NewtonStats,
    pins: np.ndarray | None = None,
) -> np.ndarray:
    """Solve ``(H + λ I) p = rhs`` for the Gauss–Newton matrix ``H`` at ``ev``, by a fresh factorisation.

    ``pins`` (``3n``, > 0 on fixed degrees of freedom): the step is solved on the free ones only (zero elsewhere)."""
    H = assembler.assemble(ev)
    stats.hessian_assemblies += 1
    factor = assembler.matrix.factor(H, lam if pins is None else lam + pins)
    stats.linear_solves += 1
    p = factor.apply(rhs)
    return p if pins is None else p * (pins == 0)
