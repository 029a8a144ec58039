"""The solver's tail and saddle handling: exact Hessian, inertia of the block factorisation, the escape from a
saddle, and the smooth cap of the face-angle energy at squashed corners."""

from __future__ import annotations

import copy
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from curved_fold.core.solve import forces as F  # noqa: N812
from curved_fold.core.solve import newton
from curved_fold.core.solve.linalg import BlockTridiagonal
from curved_fold.core.solve.model import build_model, mesh_from_triangles
from curved_fold.core.solve.newton import HessianAssembler
from curved_fold.core.solve.solver import Solver, SolverSettings
from tests.test_forces import grid_mesh


def dense(assembler: HessianAssembler, storage: np.ndarray) -> np.ndarray:
    """The symmetric matrix held in the assembler's ``storage`` as a dense array (natural dof order)."""
    return assembler.matrix.dense(storage)


def finite_difference_hessian(model, x, theta, percent, eps=1e-6):
    n = x.size
    H = np.zeros((n, n))
    for k in range(n):
        xp, xm = x.copy().reshape(-1), x.copy().reshape(-1)
        xp[k] += eps
        xm[k] -= eps
        fp = F.evaluate(model, xp.reshape(x.shape), theta, percent).forces.reshape(-1)
        fm = F.evaluate(model, xm.reshape(x.shape), theta, percent).forces.reshape(-1)
        H[:, k] = -(fp - fm) / (2 * eps)
    return H


@pytest.mark.parametrize("seed", [0, 1])
def test_exact_hessian_is_the_derivative_of_the_forces(seed):
    """Bars, hinges k∇θ∇θᵀ + k(θ−θ̄)∇²θ and faces φ''∇α∇αᵀ + φ'∇²α, assembled, equal −∂F/∂x (central differences)."""
    mesh = grid_mesh(3, 3, creases={(1, 5): ("V", 90.0), (5, 9): ("M", -60.0), (2, 6): ("U", np.nan)})
    model = build_model(mesh)
    x = model.rest + np.random.default_rng(seed).normal(0, 0.08, model.rest.shape)
    theta = F.fold_angles(model, x)
    ev = F.evaluate(model, x, theta, 0.7, jacobians=True)
    assembler = HessianAssembler(model)
    H = dense(assembler, assembler.assemble_exact(x, ev))
    fd = finite_difference_hessian(model, x, theta, 0.7)
    assert np.max(np.abs(H - fd)) < 1e-6 * np.max(np.abs(H))
    gn = dense(assembler, assembler.assemble(ev))
    assert np.max(np.abs(gn - fd)) > 1e-3 * np.max(np.abs(H))  # Gauss–Newton misses the curvature terms


def test_inertia_and_negative_direction_of_the_block_factorisation():
    """The factorisation counts the negative eigenvalues of an indefinite matrix exactly (Sylvester) and its
    negative-curvature direction has wᵀAw < 0."""
    rng = np.random.default_rng(3)
    n = 60
    pairs = np.array([[i, i + 1] for i in range(n - 1)] + [[i, i + 2] for i in range(n - 2)])
    bt = BlockTridiagonal(n, pairs, min_block=4)
    rows = np.concatenate([pairs[:, 0], pairs[:, 1], np.arange(n)])
    cols = np.concatenate([pairs[:, 1], pairs[:, 0], np.arange(n)])
    blocks = rng.normal(size=(len(rows), 3, 3))
    blocks[: len(pairs)] *= 0.3
    blocks[len(pairs) : 2 * len(pairs)] = blocks[: len(pairs)].transpose(0, 2, 1)
    diag = blocks[2 * len(pairs) :]
    diag[:] = 0.5 * (diag + diag.transpose(0, 2, 1)) + 2.0 * np.eye(3)
    diag[7] -= 6.0 * np.eye(3)  # a few negative directions
    diag[40, 0, 0] -= 5.0
    storage = bt.assemble(bt.scatter_index(rows, cols), blocks)
    A = np.zeros((3 * n, 3 * n))
    for r, c, b in zip(rows, cols, blocks, strict=True):
        A[3 * r : 3 * r + 3, 3 * c : 3 * c + 3] += b
    factor = bt.factor(storage, 0.0, inertia=True)
    assert factor.negative_pivots == int(np.sum(np.linalg.eigvalsh(A) < 0)) >= 3
    w = factor.negative_direction()
    assert w is not None and w @ A @ w < 0
    spd = bt.factor(storage, 12.0, inertia=True)
    assert spd.negative_pivots == 0 and spd.negative_direction() is None


def buckling_solver(exact_tail: bool) -> Solver:
    """A flat grid whose interior bars are 8 % too long, held by a border ring at rest length: the flat in-plane
    equilibrium is a saddle (the compressed interior wants to bulge out of plane, to either side)."""
    mesh = grid_mesh(6, 6, 60.0)
    solver = Solver(mesh, SolverSettings(exact_tail=exact_tail, max_iterations=400))
    m = solver.model
    border = np.isin(mesh.assignments, ("B",))
    m.bar_length[~border] *= 1.08
    return solver


def test_saddle_is_left_along_negative_curvature_to_a_stable_minimum():
    flat = buckling_solver(exact_tail=False).solve(0.0, continuation=False)
    assert flat.converged and np.ptp(flat.positions[:, 2]) < 1e-9  # Gauss–Newton stays on the symmetric saddle
    solver = buckling_solver(exact_tail=True)
    x = solver.model.from_mm(flat.positions)
    assert solver.negative_pivots(x, flat.theta, 0.0) > 0  # it is a saddle, not a minimum
    bulged = solver.solve(0.0, continuation=False)
    assert bulged.converged, bulged.message
    assert bulged.saddle_escapes >= 1
    assert np.ptp(bulged.positions[:, 2]) > 1.0  # mm: out of plane
    assert bulged.energy < flat.energy * (1 - 1e-3)
    x = solver.model.from_mm(bulged.positions)
    assert solver.negative_pivots(x, bulged.theta, 0.0) == 0


def test_a_saddle_is_left_on_the_side_the_branch_chooser_picks_whatever_the_round_off():
    """At the symmetric saddle of the buckling grid (bulge up or down, equal energies, zero gradient) the side
    taken depends neither on the round-off in the gradient (mirrored here: ±1e-12 along the negative direction)
    nor on the signs the factorisation gives the pivots' eigenvectors (LAPACK, numpy version): every variant lands
    on the same state, the side :func:`newton.branch_chooser` picks."""
    flat = buckling_solver(exact_tail=False).solve(0.0, continuation=False)
    solver = buckling_solver(exact_tail=True)
    model = solver.model
    x = model.from_mm(flat.positions)
    ev = F.evaluate(model, x, flat.theta, 0.0, jacobians=True)
    H = solver.assembler.assemble_exact(x, ev)
    shift = 1e-7 * solver.force_scale + newton.rigid_shift(x, ev.forces)
    factor = solver.assembler.matrix.factor(H, shift, inertia=True)
    assert factor.negative_pivots > 0
    w = factor.negative_subspace_direction(newton.branch_chooser(model.n_nodes)).reshape(-1, 3)
    flipped = copy.copy(factor)  # the same factorisation, every negative eigenvector with the other sign
    flipped.negative_pairs = [(k, vals, -vecs) for k, vals, vecs in factor.negative_pairs]

    escapes = []
    for noise in (1e-12, -1e-12):
        tilted = dataclasses.replace(ev, forces=ev.forces + noise * w)
        for f in (factor, flipped):
            escapes.append(newton._saddle_step(model, f, x, tilted, 0.0, newton.NewtonStats(), newton.Fixed()))
    assert all(e is not None for e in escapes)
    for e in escapes[1:]:
        np.testing.assert_array_equal(e[0], escapes[0][0])
    assert np.ptp(escapes[0][0][:, 2]) > 0 and escapes[0][1].energy < ev.energy
    step = escapes[0][0] - x
    assert float(np.dot(newton.branch_chooser(model.n_nodes), step.reshape(-1))) > 0


def test_gauss_newton_steps_are_stretched_rolling_off_a_saddle(monkeypatch):
    """Just off the buckling grid's saddle, Gauss–Newton (blind to the negative curvature) rolls down to the bulged
    minimum with steps that only grow slowly; stretched (2p, 4p while the energy keeps falling) it gets there in
    fewer iterations, to the same state."""
    flat = buckling_solver(exact_tail=False).solve(0.0, continuation=False)
    solver = buckling_solver(exact_tail=False)
    model = solver.model
    x = model.from_mm(flat.positions)
    nudge = 1e-4 * newton.branch_chooser(model.n_nodes).reshape(-1, 3) * np.array([0.0, 0.0, 1.0])
    runs, default = {}, newton.STRETCH
    for stretch in (default, 1.0):
        monkeypatch.setattr(newton, "STRETCH", stretch)
        xs, _, ev, stats, _ = newton.newton_solve(
            model,
            x + nudge,
            flat.theta,
            0.0,
            force_scale=solver.force_scale,
            tolerance=1e-8,
            max_iterations=400,
            exact_tail=False,
            check_minimum=False,
        )
        assert stats.converged
        runs[stretch] = (xs, ev.energy, stats)
    (xs, energy, stretched), (x1, energy1, plain) = runs[default], runs[1.0]
    assert stretched.stretched_steps > 0 and plain.stretched_steps == 0
    assert stretched.iterations < plain.iterations
    assert abs(energy - energy1) <= 1e-9 * abs(energy1)
    assert np.max(np.abs(xs - x1)) < 1e-4  # the same bulge (normalised units)
    assert np.ptp(model.to_mm(xs)[:, 2]) > 1.0


def test_exact_tail_converges_quadratically():
    """From residual 1e-4 the exact Hessian reaches 1e-10 within three iterations (measured: 1.8e-5, 2.1e-7,
    1.7e-11); Gauss–Newton alone is linear (×0.15 per iteration here, seven iterations)."""
    from tests.test_solver_fixtures import fixture_mesh

    mesh = fixture_mesh("curvedPleatSimple.svg")
    counts = {}
    for exact in (True, False):
        solver = Solver(mesh, SolverSettings(tolerance=1e-10, exact_tail=exact, max_iterations=400))
        residuals = [p.residual for p in solver.solve_steps(0.6, continuation=False)]
        assert residuals[-1] <= 1e-10
        counts[exact] = sum(1 for r in residuals if 1e-10 < r < 1e-4)
    assert counts[True] <= 3 < counts[False], counts


def squashed_triangle(lift: float) -> tuple:
    """A triangle (0.04° corner at node 2 when flat) whose apex is pushed through the line of its base by ``lift``."""
    verts = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 3e-4]])
    mesh = mesh_from_triangles(verts, np.array([[0, 1, 2]]))
    model = build_model(mesh, axial_stiffness=0.0, face_stiffness=0.2)
    x = model.rest.copy()
    x[2, 1] = model.rest[0, 1] + lift
    return model, x


def test_face_angle_energy_is_smooth_through_a_squashed_triangle():
    """Across the squashed state (corner 180°) the force is continuous and bounded (it vanishes there), and it is
    still the exact negative gradient of the capped energy."""
    forces = []
    for lift in (-1e-6, -1e-9, 1e-9, 1e-6):
        model, x = squashed_triangle(lift)
        ev = F.evaluate(model, x, None, 0.0)
        forces.append(ev.forces)
    jump = np.max(np.abs(forces[1] - forces[2]))
    assert jump < 1e-3 * max(np.max(np.abs(f)) for f in forces) + 1e-9
    model, x = squashed_triangle(1e-4)  # inside the cap (the corner is within 0.03° of 180°)
    ev = F.evaluate(model, x, None, 0.0)
    eps = 1e-8
    fd = np.zeros_like(x)
    for i in range(3):
        for k in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, k] += eps
            xm[i, k] -= eps
            fd[i, k] = -(F.evaluate(model, xp, None, 0.0).energy - F.evaluate(model, xm, None, 0.0).energy) / (2 * eps)
    assert np.max(np.abs(fd - ev.forces)) < 1e-3 * np.max(np.abs(ev.forces))  # arccos near 180°: FD noise ~1e-4


def test_face_angle_energy_is_origami_simulators_away_from_the_caps():
    alpha0 = np.radians(np.array([[30.0, 60.0, 90.0]]))
    alpha = alpha0 + np.radians(5.0)
    phi, dphi, ddphi = F.face_angle_energy(alpha, alpha0, 0.2)
    assert np.allclose(phi, 0.5 * 0.2 * (alpha - alpha0) ** 2) and np.allclose(dphi, 0.2 * (alpha - alpha0))
    squashed = F.face_angle_energy(np.array([0.0, np.pi]), np.radians(np.array([30.0, 150.0])), 0.2)
    assert np.all(squashed[1] == 0) and np.all(np.isfinite(squashed[0]))  # zero slope at 0° and 180°


def test_static_fold_reports_the_state_and_where_another_branches_off():
    """A static fold (continuation) that had to leave a saddle says so: a stable minimum with its energy, and the
    fold percent where the other branch is."""
    from curved_fold.core.pipeline import state_report

    solver = buckling_solver(exact_tail=True)
    result = solver.solve(0.0)  # from the flat sheet: continuation, converged only at a minimum
    assert result.converged and result.continuation_steps == 1
    assert result.saddle_escapes >= 1 and result.saddle_percents == [0.0]
    report = state_report(result)
    assert report["negative_pivots"] == 0
    assert report["state"] == f"stable minimum (energy {result.energy:.6g})"
    assert "passed a saddle near 0 %" in report["other_state_near"]
    plain = state_report(Solver(grid_mesh(3, 3, creases={(1, 5): ("V", 90.0)}), SolverSettings()).solve(0.6))
    assert plain["state"].startswith("stable minimum") and "other_state_near" not in plain
    # stopped at the iteration cap: no equilibrium, whatever the pivots of where it stopped say
    capped = Solver(grid_mesh(3, 3, creases={(1, 5): ("V", 90.0)}), SolverSettings(max_iterations=1)).solve(0.6)
    assert not capped.converged and capped.negative_pivots == 0
    report = state_report(capped)
    assert report["state"] == f"not an equilibrium: the solve stopped before it converged (energy {capped.energy:.6g})"


def test_gauss_newton_assembly_equals_its_matrix_free_product():
    """The assembled Gauss–Newton matrix (batched outer products scattered into block storage) times v equals the
    element-by-element product ``forces.hessian_matvec`` (the faithful time-step bound's power iteration): two
    independent codings of one matrix."""
    mesh = grid_mesh(4, 3, creases={(1, 6): ("V", 90.0), (6, 11): ("M", -60.0), (2, 7): ("U", np.nan)})
    model = build_model(mesh)
    rng = np.random.default_rng(3)
    x = model.rest + rng.normal(0, 0.05, model.rest.shape)
    ev = F.evaluate(model, x, F.fold_angles(model, x), 0.8, jacobians=True)
    assembler = HessianAssembler(model)
    assembler.assemble_exact(x, ev)  # the two assemblies share a value buffer: the second must not see the first
    G = dense(assembler, assembler.assemble(ev))
    for _ in range(3):
        v = rng.normal(size=x.shape)
        np.testing.assert_allclose(
            G @ v.reshape(-1), F.hessian_matvec(model, ev, v).reshape(-1), atol=1e-9 * np.abs(G).max()
        )


def test_rigid_shift_is_the_exact_curvature_of_the_rotations():
    """``newton.rigid_shift`` reads the curvature of the three rigid rotations from the forces alone
    (uᵀ∇²E u = F · (ω × (ω × r)), the energy being invariant under rotation). Checked against the assembled exact
    Hessian on a perturbed, out-of-equilibrium creased grid: the lowest generalised eigenvalue of the rotations' block
    (against their Gram matrix) is what the shift lifts, so shifting by it leaves them non-negative."""
    from curved_fold.core.solve.newton import rigid_shift

    mesh = grid_mesh(3, 3, creases={(1, 5): ("V", 90.0), (5, 9): ("M", -60.0)})
    model = build_model(mesh)
    shifts = []
    for seed in range(4):
        # stretched (seeds 0, 1: the rotations' curvature is positive) and compressed sheets (2, 3: negative)
        scale = 1.1 if seed < 2 else 0.9
        x = scale * model.rest + np.random.default_rng(seed).normal(0, 0.02, model.rest.shape)
        ev = F.evaluate(model, x, F.fold_angles(model, x), 0.7 + 0.5 * seed, jacobians=True)
        assembler = HessianAssembler(model)
        H = dense(assembler, assembler.assemble_exact(x, ev))
        r = x - x.mean(axis=0)
        U = np.stack([np.cross(e, r).reshape(-1) for e in np.eye(3)], axis=1)
        li = np.linalg.inv(np.linalg.cholesky(U.T @ U))
        lowest = np.linalg.eigvalsh(li @ (U.T @ H @ U) @ li.T)[0]
        shift = rigid_shift(x, ev.forces)
        assert shift == pytest.approx(2.0 * max(0.0, -lowest), rel=1e-9, abs=1e-12)
        assert np.linalg.eigvalsh(li @ (U.T @ H @ U) @ li.T + shift * np.eye(3))[0] >= -1e-9
        shifts.append(shift)
    assert shifts[0] == shifts[1] == 0.0 and min(shifts[2:]) > 0.0


def test_repeated_saddle_escapes_follow_the_curve_out(monkeypatch):
    """A circular pleat drawn with CSS classes (eleven rings, ``tests/data/circular_pleat_css.svg``) leaves several
    saddles on its way to 100 %. From the third escape of a solve on, an escape follows the curve out of the saddle
    (``newton.CURVED_ESCAPES_AFTER``): the same minimum in fewer iterations and escapes (measured 51 and 4 against
    65 and 6 straight). A designer's edited CircularPleat crept so for 200 escapes, 500 iterations (367 now)."""
    from pathlib import Path

    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.mesh.build import build_mesh
    from curved_fold.core.solve.solver import Solver

    mesh = build_mesh(read_pattern(Path(__file__).parent / "data" / "circular_pleat_css.svg"))
    curved = Solver(mesh).solve(1.0)
    monkeypatch.setattr(newton, "CURVED_ESCAPES_AFTER", 10**9)
    straight = Solver(mesh).solve(1.0)
    for r in (curved, straight):
        assert r.converged and r.negative_pivots == 0, r.message
    assert abs(curved.energy - straight.energy) <= 1e-8 * straight.energy
    assert curved.saddle_escapes >= 3 and curved.saddle_escapes < straight.saddle_escapes
    assert curved.iterations <= straight.iterations - 8, (curved.iterations, straight.iterations)


def test_projected_part_of_element_blocks_is_their_positive_semidefinite_part():
    """The rescue's projection (``newton._psd_part``) through the complement of the translations equals the full
    eigendecomposition's positive part for blocks that no translation changes, and is positive semidefinite."""
    rng = np.random.default_rng(5)
    for nodes in (3, 4):
        q = 3 * nodes
        Q = newton._translation_complement(nodes)
        reduced = rng.standard_normal((20, q - 3, q - 3))
        blocks = Q @ (reduced + reduced.transpose(0, 2, 1)) @ Q.T  # symmetric, translations in the null space
        w, v = np.linalg.eigh(blocks)
        expected = (v * np.maximum(w, 0.0)[:, None, :]) @ v.transpose(0, 2, 1)
        projected = blocks.copy()
        newton._psd_part(projected)
        np.testing.assert_allclose(projected, expected, atol=1e-12 * np.abs(expected).max())
        assert np.linalg.eigvalsh(projected).min() > -1e-12 * np.abs(expected).max()


@pytest.mark.slow
def test_the_rescue_leaves_folds_that_converge_within_its_threshold_unchanged_and_folds_a_crumpling_grid(monkeypatch):
    """The projected-Newton rescue (``newton.RESCUE_AFTER``) only acts past 100 iterations of one solve: a fixture
    folds bit for bit as without it. The designer's curved Miura (tests/data/sine_rows_crossed.svg) uses it in its
    last two stages and still folds to a stable minimum (numpy 1.26: 343 iterations instead of 630, another minimum,
    E 13.815 instead of 13.880)."""
    from pathlib import Path

    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.pipeline import fold_pattern

    data = Path(__file__).resolve().parent
    runs = {}
    for rescue in (True, False):
        monkeypatch.setattr(newton, "RESCUE", rescue)
        pleat = fold_pattern(read_pattern(data / "fixtures" / "origami-simulator" / "Rotating_Star.svg"), percent=1.0)
        grid = fold_pattern(read_pattern(data / "data" / "sine_rows_crossed.svg"), percent=1.0)
        runs[rescue] = pleat, grid
    (pleat, grid), (plain_pleat, plain_grid) = runs[True], runs[False]
    assert pleat.report["iterations"] == plain_pleat.report["iterations"]
    assert np.array_equal(pleat.result.positions, plain_pleat.result.positions)
    for run in (grid, plain_grid):
        assert run.report["converged"] and run.report["negative_pivots"] == 0, run.report["message"]
    assert "projected-Newton rescue steps" in grid.result.message
    assert "rescue" not in plain_grid.result.message


def test_a_rescue_whose_every_try_is_rejected_does_not_poison_the_next(monkeypatch):
    """When every try of a projected-Newton rescue step is rejected, the damping it returns has grown by 2^78; kept,
    it made every later rescue of the solve fail too (twelve factorisations each, none accepted). The next try now
    starts from ten times the damping before, at most ``RESCUE_MU_MAX``, and the 3-row curved Miura still converges
    with rescue steps taken after the failure."""
    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.pipeline import fold_pattern
    from curved_fold.core.solve import newton

    real, calls = newton._projected_step, []

    def once_rejected(model, assembler, x, ev, rhs, mu, *rest):
        calls.append(mu)
        if len(calls) == 3:
            return None, mu * 2.0**78
        step, nxt = real(model, assembler, x, ev, rhs, mu, *rest)
        calls[-1] = (mu, step is not None)
        return step, nxt

    monkeypatch.setattr(newton, "_projected_step", once_rejected)
    run = fold_pattern(read_pattern(Path(__file__).resolve().parent / "data" / "sine_rows_crossed.svg"), percent=1.0)
    after = calls[3:]
    assert run.report["converged"] and after
    assert all(mu <= newton.RESCUE_MU_MAX for mu, _ in after) and any(ok for _, ok in after)
