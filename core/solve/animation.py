"""Per-frame folding: the fold percent changes every frame and each frame warm-starts from the previous one.

Two modes:

* ``"quasi_static"`` — equilibrium per frame with the fast solver. A frame a small step after the last one (between
  the same two grid points of the natural path, :func:`.path.warm_startable`) is warm-started from the last
  positions and fold angles (θ history, so hinges keep unwrapping past ±180°), extrapolated linearly in the fold
  percent from the last two equilibria (a predictor along the folding path; the Newton solve is the corrector),
  limited to steps no larger than the last one, in at most :data:`.path.WARM_MAX_ITERATIONS`. Any other frame (the
  first, a jump, a grid point crossed, a step back, a warm frame that did not converge in its cap) is solved from
  the natural path like a static fold (:meth:`.Solver.fold_steps`, whose grid states the solver keeps): it *is*
  the static fold at its percent, also where a pattern has several equilibria. Warm frames follow the fold more
  finely than the static fold's one step from the last grid point; where a pattern branches inside that step
  (concentric circles folded to 150°, docs/solver.md) the last frame can settle in a neighbouring stable state.
* ``"dynamic"`` — Origami Simulator's behaviour: ``steps_per_frame`` explicit steps per frame with velocities carried
  over (no convergence test), like the app's 100 steps per rendered frame.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .. import run_to_end
from ..mesh.fold_mesh import FoldMesh
from .path import WARM_MAX_ITERATIONS, extrapolate, warm_startable
from .solver import Solver, SolverSettings


@dataclass
class FrameResult:
    """One frame: ``positions`` ``(n, 3)`` mm, fold angles per edge (deg), iterations (Newton iterations or
    explicit steps), wall ``ms``, whether it ``converged`` and its scale-free residual."""

    positions: np.ndarray
    fold_angles: np.ndarray
    iterations: int
    ms: float
    converged: bool
    residual: float


class FoldAnimation:
    """Stateful per-frame solver for one mesh (see module docstring)."""

    def __init__(
        self,
        mesh: FoldMesh,
        settings: SolverSettings | None = None,
        mode: str = "quasi_static",
        steps_per_frame: int = 100,
    ):
        if mode not in ("quasi_static", "dynamic"):
            raise ValueError(f"unknown animation mode {mode!r}: use 'quasi_static' or 'dynamic'")
        self.mode = mode
        self.steps_per_frame = int(steps_per_frame)
        self.solver = Solver(mesh, settings, "fast" if mode == "quasi_static" else "faithful")
        self.positions = mesh.vertices_3d.copy()
        self.theta = np.zeros(len(self.solver.model.hinge_k))
        self.velocities = np.zeros_like(self.positions)
        self._previous: tuple[float, np.ndarray, np.ndarray] | None = None
        self.percent: float | None = None

    def _predict(self, percent: float) -> tuple[np.ndarray, np.ndarray]:
        """Start of the next quasi-static solve: the last equilibrium, extrapolated linearly in the fold percent
        (:func:`.path.extrapolate`; none while reversing or jumping further than the last step)."""
        if self.percent is None:
            return self.positions, self.theta
        return extrapolate(percent, (self.percent, self.positions, self.theta), self._previous)

    def frame(self, percent: float) -> FrameResult:
        """Advance to fold percent ``percent`` (1.0 = 100 %) and return the frame."""
        t0 = time.perf_counter()
        if self.mode == "quasi_static":
            start, theta = None, None
            if warm_startable(self.percent, percent, self.solver.settings.continuation_step):
                start, theta = self._predict(percent)
            r = run_to_end(self.solver.frame_steps(percent, start, theta, WARM_MAX_ITERATIONS))
            if r.continuation_steps:  # from the natural path; its state at the grid point before is the next anchor
                self._previous = self.solver.path_state(percent)
            else:
                self._previous = (self.percent, self.positions, self.theta)
            self.percent = float(percent)
        else:
            r = self.solver.solve(
                percent,
                start=self.positions,
                theta_prev=self.theta,
                velocities=self.velocities,
                max_steps=self.steps_per_frame,
                stop_on_convergence=False,
            )
            self.velocities = r.velocities
        self.positions, self.theta = r.positions, r.theta
        iterations = r.iterations - r.reused_iterations  # this frame's, not those of the kept path states
        return FrameResult(
            r.positions, r.fold_angles, iterations, (time.perf_counter() - t0) * 1000.0, r.converged, r.residual
        )
