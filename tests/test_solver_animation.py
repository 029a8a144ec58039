"""Per-frame stepping: warm-started quasi-static frames and Origami Simulator-style dynamic frames."""

from __future__ import annotations

from pathlib import Path

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


def test_natural_path_grid_and_which_frames_may_warm_start():
    """The path's grid does not move with the fold percent; a frame warm-starts only a small step forward within
    one grid step, else it is solved from the path."""
    from curved_fold.core.solve.path import grid_below, steps_to, warm_startable

    assert [steps_to(p, 0.25) for p in (0.0, 0.1, 0.25, 0.26, 0.6, 1.0)] == [1, 1, 1, 2, 3, 4]
    assert grid_below(0.6, 0.25) == 0.5 and grid_below(0.5, 0.25) == 0.25 and grid_below(0.2, 0.25) == 0.0
    assert grid_below(-0.6, 0.25) == -0.5
    assert warm_startable(0.54, 0.6, 0.25)  # same cell, small step
    assert not warm_startable(0.48, 0.6, 0.25)  # a grid point (0.5) crossed
    assert not warm_startable(0.5, 0.6, 0.25)  # the frame at the grid point is not the path's state there
    assert not warm_startable(0.8, 1.0, 0.25)  # a jump of 20 %: from the path
    assert not warm_startable(0.6, 0.55, 0.25)  # backwards
    assert not warm_startable(None, 0.3, 0.25)
    assert warm_startable(-0.54, -0.6, 0.25) and not warm_startable(0.54, -0.6, 0.25)


def test_a_fold_from_the_kept_path_equals_a_fresh_one_and_reports_the_same_counts():
    """The solver keeps the path's grid states: a second fold (or an animation frame solved from the path) reuses
    them, runs only its last step, and reports the same state and counts as a fresh solver."""
    from curved_fold.core.solve.solver import Solver

    mesh = crease_grid()
    fresh = Solver(mesh, SolverSettings()).solve(0.9)
    solver = Solver(mesh, SolverSettings())
    solver.solve(0.6)  # computes and keeps the grid states at 25 % and 50 %
    again = solver.solve(0.9)
    assert again.reused_iterations > 0 and fresh.reused_iterations == 0
    assert np.array_equal(again.positions, fresh.positions)
    assert (again.iterations, again.force_evaluations, again.continuation_steps) == (
        fresh.iterations,
        fresh.force_evaluations,
        fresh.continuation_steps,
    )


def test_frames_that_jump_are_the_static_fold_at_their_percent():
    """A frame solved from the natural path (the first, a jump, a grid point crossed, a step back) is the static fold
    at its percent, bit for bit, whatever frames came before."""
    from curved_fold.core.solve.solver import Solver

    mesh = crease_grid()
    anim = FoldAnimation(mesh, SolverSettings())
    for p in (0.1, 0.15, 0.2, 0.3, 0.7, 0.4):
        f = anim.frame(p)
        if p in (0.1, 0.3, 0.7, 0.4):
            assert np.array_equal(f.positions, Solver(mesh, SolverSettings()).solve(p).positions)


def test_a_warm_frame_that_does_not_converge_in_its_cap_is_the_static_fold():
    """simpleVertex over 100 frames: the warm step to 59 % slides for more than ``WARM_MAX_ITERATIONS`` (its branch
    loses its stability there); the frame is then solved from the natural path, as the static fold at 59 % exactly,
    and every frame converges."""
    from curved_fold.core.solve.path import WARM_MAX_ITERATIONS, warm_startable
    from curved_fold.core.solve.solver import Solver
    from tests.test_solver_fixtures import fixture_mesh

    mesh = fixture_mesh("simpleVertex.svg")
    anim = FoldAnimation(mesh, SolverSettings())
    fell_back, previous = [], None
    for k in range(1, 101):
        f = anim.frame(k / 100)
        assert f.converged, k
        if warm_startable(previous, k / 100, 0.25) and f.iterations > WARM_MAX_ITERATIONS:
            assert np.array_equal(f.positions, Solver(mesh, SolverSettings()).solve(k / 100).positions), k
            fell_back.append(k)
        previous = k / 100
    assert fell_back


def test_the_last_frame_sits_where_the_static_fold_does():
    """The energy does not see rigid motions, so a solve left the sheet where its damped steps carried it: the last
    of 30 warm frames had the static fold's shape to 1e-8 but sat 0.4 % of the diagonal away from it (a baked
    animation jumped off the Fold it ends on). Every fast result now has the sheet's centre face on the table
    (``core.solve.pose``): the same place, not only the same shape, and that face where it was drawn."""
    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.mesh.build import build_mesh
    from curved_fold.core.solve.pose import reference_triangle
    from curved_fold.core.solve.solver import Solver

    mesh = build_mesh(read_pattern(Path(__file__).resolve().parents[1] / "examples" / "concentric_arcs.svg"))
    static = Solver(mesh, SolverSettings()).solve(1.0).positions
    anim = FoldAnimation(mesh, SolverSettings())
    for k in range(1, 31):
        last = anim.frame(k / 30)
        assert last.converged, k
    assert np.abs(last.positions - static).max() <= 1e-5 * mesh.diagonal
    face = reference_triangle(mesh)
    assert np.abs(static[face] - mesh.vertices_3d[face]).max() <= 1e-3 * mesh.diagonal


DISC_SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100">
<rect x="0" y="0" width="100" height="100" stroke="#000" fill="none"/>
<circle cx="50" cy="50" r="20" stroke="#0f0" fill="none"/>
<path d="M 0 10 C 30 20, 70 0, 100 10" stroke="#00f" stroke-opacity="0.5" fill="none"/>
<path d="M 35 40 C 45 55, 55 45, 65 60" stroke="#f00" stroke-opacity="0.5" fill="none"/>
</svg>"""


def test_a_loose_piece_rests_on_its_own_centre_face():
    """A hole drawn as a closed cut leaves a loose disc (warned), folding on its own: it rests on its own centre face,
    so it too sits in the same place in the last frame as in the static fold (placed with the sheet's face, it kept
    the drift of its path)."""
    from curved_fold.core.io.svg import parse_svg_text
    from curved_fold.core.mesh.build import build_mesh
    from curved_fold.core.pattern.discretize import discretize
    from curved_fold.core.solve.pose import resting_pieces
    from curved_fold.core.solve.solver import Solver

    mesh = build_mesh(discretize(parse_svg_text(DISC_SVG, "disc.svg").curves))
    pieces = resting_pieces(mesh)
    assert sorted(len(v) for v, _ in pieces) == [76, 168]
    static = Solver(mesh, SolverSettings()).solve(1.0).positions
    anim = FoldAnimation(mesh, SolverSettings())
    for k in range(1, 21):
        last = anim.frame(k / 20)
    assert last.converged
    assert np.abs(last.positions - static).max() <= 1e-4 * mesh.diagonal
    for _, face in pieces:
        assert np.abs(static[face] - mesh.vertices_3d[face]).max() <= 1e-3 * mesh.diagonal
