"""The natural folding path: continuation in the fold percent from the flat sheet through fixed grid points.

A fold to ``P`` walks the grid ``±k · step`` (``k = 1, 2, …``, ``step`` = ``SolverSettings.continuation_step``) up
to the last point before ``P``, then steps to ``P``. The grid does not depend on ``P``, so the states at its points
(:class:`PathState`, cached by :class:`~.solver.Solver`) are *the* path: a static fold at ``P`` and every animation
frame that is solved from the path (:func:`warm_startable` false) continue from the same state at the same grid
point, with the same predictor, and reach the same equilibrium — bit for bit — wherever the pattern has several
(a rotationally symmetric pleat passing a cascade of symmetric saddles, CircularPleat-antiFacet; docs/solver.md,
"One natural state"). With equal steps of ``P / n`` (before the seventh pass) the path's points moved with ``P``
and a static fold at 60 % and the last of five animation frames ended in different minima.

Plain data and arithmetic only: the solves are :class:`~.solver.Solver`'s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

EXACT_RETRY = True
"""A path stage that stalls is solved once more from the same predictor with the exact Hessian from its first
iteration instead of Gauss–Newton far from equilibrium, before it is halved (the other fuzz pattern left open in
the seventh pass, seed 42: two −179° mountains crossing on a 20 mm sheet, stalled at 100 % at residual 24 even
after three halvings; with the retry it converges to a stable minimum with numpy 1.26, and still stalls with numpy
2.5's round-off). Patterns that do not stall are unchanged."""

MAX_HALVINGS = 3
"""A path stage that stalls ("no descent step": a Newton step from the predictor lands where a wing squashed onto
its hinge line makes the energy too steep to descend), and stalls again when solved once more with the exact Hessian
from its first iteration (:meth:`.solver.Solver.fold_steps`), is taken again in two halves, down to ⅛ of the step.
A fuzzed pattern (tools/fuzz_long.py, seed 7) stalled at residual 2.4e2 in the 75 → 100 % step, a mountain crease's
wing a 174° triangle; from its state at 87.5 % it converges (45 iterations)."""


WARM_MAX_ITERATIONS = 40
"""Newton iterations an animation frame warm-started from the frame before (:func:`warm_startable`) may take
before it is solved again from the natural path, as the static fold at its percent (:class:`.animation.FoldAnimation`
and the timeline's bakes; playback, synchronous, keeps its own smaller cap). Warm frames of the fixtures converge in
2–21 iterations (Gauss–Newton, linear near a soft mode). One that needs more has lost the branch it followed: with
concentric circles folded to 150°, the warm step from 85 % to 90 % slid round a saddle for 500 iterations and did not
converge; solved from the path, the frame converges in 59 (its static fold). With 40, a 101-frame animation of the
fixtures costs what it did without a cap."""


@dataclass
class PathState:
    """A converged state of the natural path at grid point ``percent`` (fraction): normalised positions ``x``, θ
    history, the Levenberg–Marquardt damping the next stage starts from, the counts of the whole path up to here
    (``totals``: iterations, evaluations, …) and the fold percents where saddles were left on the way."""

    percent: float
    x: np.ndarray
    theta: np.ndarray
    lm_lambda: float
    totals: dict[str, int]
    saddle_percents: list[float] = field(default_factory=list)


def steps_to(percent: float, step: float) -> int:
    """Number of continuation steps of a fold from the flat sheet to ``percent``: ``⌈|percent| / step⌉`` (≥ 1);
    the grid points passed are :func:`grid_point` ``(k, percent, step)`` for ``k < steps_to(…)``."""
    return max(1, int(math.ceil(abs(float(percent)) / max(step, 1e-6) - 1e-9)))


def grid_point(k: int, percent: float, step: float) -> float:
    """The ``k``-th grid point on the way to ``percent`` (0: the flat sheet), on ``percent``'s side of 0."""
    return math.copysign(k * max(step, 1e-6), float(percent)) if k else 0.0


def grid_below(percent: float, step: float) -> float:
    """The last grid point strictly before ``percent`` on the path from the flat sheet (0.0 within the first step)."""
    return grid_point(steps_to(percent, step) - 1, percent, step)


def extrapolate(
    percent: float,
    last: tuple[float, np.ndarray, np.ndarray],
    before: tuple[float, np.ndarray, np.ndarray] | None,
) -> tuple[np.ndarray, np.ndarray]:
    """The predictor along the folding path: positions and θ of the equilibrium ``last`` = ``(percent, x, θ)``,
    extrapolated linearly in the fold percent from ``before`` (the equilibrium before it on the path) to
    ``percent``, when that step is no longer than theirs and goes the same way; else ``last``'s as they are (no
    equilibrium before, a step back, or a jump further than the last step). Newton is the corrector. Used by the
    path's stages, the quasi-static animation and the timeline's frames alike."""
    q, x, theta = last
    if before is None or before[0] == q:
        return x, theta
    s = (float(percent) - q) / (q - before[0])
    if not 0.0 < s <= 1.0:
        return x, theta
    return x + s * (x - before[1]), theta + s * (theta - before[2])


def warm_startable(previous: float | None, percent: float, step: float) -> bool:
    """Whether a frame at ``percent`` may warm-start from an equilibrium at ``previous`` (both fractions) instead of
    being solved from the natural path: ``previous`` lies after the last grid point before ``percent`` and before
    ``percent``, on the same side of 0, at most half a step behind it.

    Small forward steps between grid points follow the path as closely as the static fold's single step does
    (measured on every fixture: the last of 10 and 20 frames equals the static fold to ≤ 1e-8 of the diagonal).
    A frame that jumps half a step or more, crosses a grid point, or goes backwards is solved from the path:
    from CircularPleat-antiFacet's state at 75 %, a 5-frame animation's frame at 80 % followed by a 20 % jump
    ended in another stable minimum than the static fold's one step from 75 % (E 5.061 against 4.728)."""
    if previous is None:
        return False
    p, q = float(percent), float(previous)
    g = grid_below(p, step)
    if p < 0:
        p, q, g = -p, -q, -g
    return g < q < p and p - q <= 0.5 * max(step, 1e-6)
