"""Per-frame stepping: warm-started quasi-static frames and Origami Simulator-style dynamic frames."""

from __future__ import annotations

import numpy as np

from curved_fold.core.solve.animation import FoldAnimation
from curved_fold.core.solve.solver import SolverSettings
from tests.test_forces import grid_mesh


def crease_grid():
    return grid_mesh(6, 6, 60.0, {(3 + 7 * j, 3 + 7 * (j + 1)): ("V", 150.0) for j in range(6)})


def test_quasi_static_frames_follow_percent_and_warm_start():
    mesh = crease_grid()
    anim = FoldAnimation(mesh, SolverSettings(tolerance=1e-6))
    crease = mesh.assignments == "V"
    first = anim.frame(0.2)
    iters = [anim.frame(p).iterations for p in np.linspace(0.22, 0.4, 10)]
    last = anim.frame(0.4)
    assert first.converged and last.converged
    assert np.median(last.fold_angles[crease]) > np.median(first.fold_angles[crease]) + 20
    assert max(iters) <= 6  # warm starts need few Newton iterations per small percent step


def test_jump_to_full_fold_in_one_frame_is_finite_and_converges():
    anim = FoldAnimation(crease_grid())
    f = anim.frame(1.0)
    assert f.converged and np.all(np.isfinite(f.positions))
    assert np.nanmax(f.fold_angles) > 140


def test_dynamic_frames_carry_velocity_and_approach_equilibrium():
    mesh = crease_grid()
    anim = FoldAnimation(mesh, mode="dynamic", steps_per_frame=100)
    residuals = [anim.frame(1.0).residual for _ in range(30)]
    assert all(np.isfinite(residuals))
    assert residuals[-1] < residuals[0]
    assert np.nanmax(anim.frame(1.0).fold_angles) > 20


def test_predictor_frames_match_cold_solves_and_survive_reversal():
    """Extrapolated starts must not change the answer: each frame equals a solve from the flat sheet, also after the
    fold percent turns round."""
    from curved_fold.core.solve.solver import rigid_rms, solve

    mesh = crease_grid()
    anim = FoldAnimation(mesh, SolverSettings(tolerance=1e-8))
    for p in (0.1, 0.2, 0.3, 0.4, 0.3, 0.2):
        f = anim.frame(p)
        assert f.converged
    cold = solve(mesh, 0.2, "fast", SolverSettings(tolerance=1e-8))
    assert rigid_rms(f.positions, cold.positions) / mesh.diagonal < 1e-5
