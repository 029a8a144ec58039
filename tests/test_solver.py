"""The solvers against exact folded shapes (ground-truth §3.3–3.4), each other, and hard cases."""

from __future__ import annotations

import numpy as np
import pytest

from curved_fold.core.solve.model import mesh_from_triangles
from curved_fold.core.solve.solver import Solver, SolverSettings, rigid_rms, solve
from tests.analytic import annular_sector, bisector_case
from tests.test_forces import grid_mesh


def stiffen_diagonals(solver: Solver, keep: np.ndarray) -> None:
    """Make facet hinges not in ``keep`` (per mesh edge) 1000× stiffer: quads stay planar (the forced case)."""
    m = solver.model
    diag = (solver.mesh.assignments[m.hinge_edge] == "F") & ~keep[m.hinge_edge]
    m.hinge_k[diag] *= 1000.0


def bisector_mesh():
    case = bisector_case()
    p = case.pattern
    creases = {
        (int(a), int(b)): (s, f)
        for (a, b), s, f in zip(p.edges, p.assignments, p.fold_angles, strict=True)
        if s in "MV"
    }
    mesh = mesh_from_triangles(p.vertices, case.ideal_triangles(), creases)
    rulings = np.array([tuple(e) in case.bisector_edges for e in mesh.edges.tolist()])
    return case, mesh, rulings


def test_bisector_mesh_folds_to_closed_form_at_measured_angle():
    case, mesh, rulings = bisector_mesh()
    solver = Solver(mesh, SolverSettings(tolerance=1e-9), "isometric")
    stiffen_diagonals(solver, rulings)
    r = solver.solve(1.0)
    assert r.converged, r.message
    crease = np.isin(mesh.assignments, ("M", "V"))
    rho = float(np.median(r.fold_angles[crease]))
    assert 110 < rho < 120  # facet bending makes the crease lag its 120° target
    err = rigid_rms(r.positions, case.folded_positions(rho)) / mesh.diagonal
    assert err <= 1e-4, err
    # the folded crease obeys κ₃D · cos(ρ/2) = κ₂D (ground-truth §3.1, §3.6). Discretely, with turning angles θ
    # (flat) and Θ (folded) at each crease vertex, this is tan(Θ/2) · cos(ρ/2) = tan(θ/2) (§3.4), exact per vertex.
    turn2 = turning_angles(np.column_stack([case.crease_points, np.zeros(len(case.crease_points))]))
    turn3 = turning_angles(r.positions[case.crease_vertices])
    ang = edge_angle_at_vertices(mesh, r.fold_angles, case.crease_vertices)
    rel = np.abs(np.tan(turn3 / 2) * np.cos(np.radians(ang) / 2) / np.tan(turn2 / 2) - 1.0)
    assert np.max(rel) < 1e-3, rel
    # and the discrete curvature version of the same relation holds to O(turn²)
    k2 = discrete_curvature(np.column_stack([case.crease_points, np.zeros(len(case.crease_points))]))
    k3 = discrete_curvature(r.positions[case.crease_vertices])
    assert np.max(np.abs(k3 * np.cos(np.radians(ang) / 2) / k2 - 1.0)) < 1e-2


def turning_angles(p: np.ndarray) -> np.ndarray:
    d = np.diff(p, axis=0)
    u = d / np.linalg.norm(d, axis=1)[:, None]
    return np.arccos(np.clip(np.einsum("ij,ij->i", u[:-1], u[1:]), -1, 1))


def discrete_curvature(p: np.ndarray) -> np.ndarray:
    """κ_i = 2 sin(turn_i / 2) / mean adjacent edge length at interior polyline vertices."""
    d = np.diff(p, axis=0)
    lengths = np.linalg.norm(d, axis=1)
    u = d / lengths[:, None]
    turn = np.arccos(np.clip(np.einsum("ij,ij->i", u[:-1], u[1:]), -1, 1))
    return 2 * np.sin(turn / 2) / (0.5 * (lengths[:-1] + lengths[1:]))


def edge_angle_at_vertices(mesh, angles, chain):
    """Mean fold angle of the two crease edges at each interior vertex of the chain."""
    lookup = {tuple(e): k for k, e in enumerate(mesh.edges.tolist())}
    per_edge = np.array([angles[lookup[(min(a, b), max(a, b))]] for a, b in zip(chain[:-1], chain[1:], strict=True)])
    return 0.5 * (per_edge[:-1] + per_edge[1:])


def sector_mesh(sector, n: int):
    """Hand mesh of the annular sector: radial lines through the crease-polygon vertices, quads split once."""
    theta = np.radians(sector.theta_deg)
    angles = -theta / 2 + np.arange(n + 1) * theta / n
    radii = [sector.r_in, sector.R, sector.r_out]
    verts = np.array([[r * np.cos(a), r * np.sin(a)] for r in radii for a in angles])
    idx = lambda ring, j: ring * (n + 1) + j  # noqa: E731
    tris = []
    for ring in range(2):
        for j in range(n):
            a, b, c, d = idx(ring, j), idx(ring, j + 1), idx(ring + 1, j + 1), idx(ring + 1, j)
            tris += [[a, c, b], [a, d, c]]  # counter-clockwise seen from +z
    creases = {(idx(1, j), idx(1, j + 1)): ("V", sector.fold_angle_deg) for j in range(n)}
    mesh = mesh_from_triangles(verts, np.array(tris), creases)
    radial = np.array([(e[1] - e[0]) == n + 1 for e in mesh.edges.tolist()])
    return mesh, radial


def test_annular_sector_folds_to_cones_with_second_order_error():
    sector = annular_sector()
    errors = []
    for n in (6, 12, 24):
        mesh, radial = sector_mesh(sector, n)
        solver = Solver(mesh, SolverSettings(tolerance=1e-9), "isometric")
        stiffen_diagonals(solver, radial)
        r = solver.solve(1.0)
        assert r.converged, r.message
        rho = float(np.median(r.fold_angles[mesh.assignments == "V"]))
        discrete = sector.discrete_positions(mesh.vertices, n, rho)
        assert rigid_rms(r.positions, discrete) / mesh.diagonal < 1e-4
        errors.append(rigid_rms(r.positions, sector.exact_positions(mesh.vertices, rho)) / mesh.diagonal)
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 1.5), (errors, orders)


def test_fast_and_faithful_agree_on_a_small_mesh():
    mesh = grid_mesh(4, 4, 80.0, {(2, 7): ("V", 100.0), (7, 12): ("V", 100.0), (12, 17): ("M", -80.0)})
    mesh.fold_angles[mesh.edges[:, 0] == -1] = 0
    settings = SolverSettings(tolerance=1e-6, max_steps=60_000)
    fast = solve(mesh, 0.8, "fast", settings)
    slow = solve(mesh, 0.8, "faithful", settings)
    assert fast.converged and slow.converged, (fast.message, slow.message)
    assert rigid_rms(fast.positions, slow.positions) / mesh.diagonal <= 1e-3
    assert fast.force_evaluations * 100 <= slow.force_evaluations
    assert abs(fast.energy - slow.energy) <= 1e-3 * max(slow.energy, 1e-12) + 1e-9


def test_full_180_fold_jump_does_not_explode():
    mesh = grid_mesh(
        4, 4, 50.0, {(2, 7): ("V", 180.0), (7, 12): ("V", 180.0), (12, 17): ("V", 180.0), (17, 22): ("V", 180.0)}
    )
    r = solve(mesh, 1.0, "fast")
    assert np.all(np.isfinite(r.positions)) and r.converged, r.message
    assert np.nanmax(r.fold_angles) > 170


def test_skinny_triangles_stay_finite_with_all_terms_time_step():
    verts = np.array([[0, 0], [100, 0], [50, 0.5], [50, -0.5], [100, 1.0]], float)
    tris = np.array([[0, 1, 2], [1, 0, 3], [1, 4, 2]])
    mesh = mesh_from_triangles(verts, tris, {(0, 1): ("V", 90.0)})
    fast = solve(mesh, 1.0, "fast")
    assert np.all(np.isfinite(fast.positions))
    slow = solve(mesh, 1.0, "faithful", SolverSettings(max_steps=3000))
    assert np.all(np.isfinite(slow.positions))


def test_all_terms_time_step_accounts_for_skinny_hinges():
    """Origami Simulator's dt sees only the shortest bar; ours shrinks with the hinge stiffness k/h² (§3.7). The
    thin pair is skinny (moment arms 2 on a 100 hinge: ours/Origami Simulator's dt 2.8 → 0.8) but not flat: a flat
    one's stiffness fades (``forces.flat_attenuation``), and with moment arms of 0.5 so does the shrinking."""
    from curved_fold.core.solve.faithful import time_step

    fat = mesh_from_triangles(
        np.array([[0, 0], [100, 0], [50, 50], [50, -50]], float), np.array([[0, 1, 2], [1, 0, 3]])
    )
    thin = mesh_from_triangles(
        np.array([[0, 0], [100, 0], [50, 2.0], [50, -2.0]], float), np.array([[0, 1, 2], [1, 0, 3]])
    )
    ratios = []
    for mesh in (fat, thin):
        s = Solver(mesh, SolverSettings(), "faithful")
        ratios.append(s.dt / time_step(s.model, "origami_simulator"))
    assert ratios[1] < 0.35 * ratios[0]


def test_all_mountain_vertex_cannot_fold_but_stays_finite():
    """Four mountains at 180° around one vertex violate Maekawa: no flat state, the solver must still end finite."""
    mesh = grid_mesh(
        2, 2, 40.0, {(1, 4): ("M", -180.0), (3, 4): ("M", -180.0), (4, 5): ("M", -180.0), (4, 7): ("M", -180.0)}
    )
    r = solve(mesh, 1.0, "fast", SolverSettings(max_iterations=100))
    assert np.all(np.isfinite(r.positions)) and np.isfinite(r.residual)
    crease = mesh.assignments == "M"
    assert np.max(np.abs(r.fold_angles[crease] + 180)) > 10  # they cannot all reach the target


@pytest.mark.slow
def test_twenty_thousand_faces_bounded():
    mesh = grid_mesh(100, 100, 200.0, {(50 + j * 101, 50 + (j + 1) * 101): ("V", 90.0) for j in range(100)})
    assert mesh.n_faces == 20000
    r = solve(mesh, 1.0, "fast", SolverSettings(max_iterations=6, tolerance=1e-5))
    assert np.all(np.isfinite(r.positions))
    assert r.iterations <= 6
    assert np.nanmax(r.fold_angles) > 60


def test_solve_steps_yields_each_iteration_and_equals_solve():
    """The sliced solve (one Newton iteration per ``next``, for Blender's modal jobs) gives exactly :meth:`solve`."""
    mesh = bisector_mesh()[1]
    whole = Solver(mesh).solve(0.8)
    steps = Solver(mesh).solve_steps(0.8)
    seen = []
    while True:
        try:
            seen.append(next(steps))
        except StopIteration as done:
            sliced = done.value
            break
    assert [p.iteration for p in seen] == list(range(1, whole.iterations + 1))
    assert seen[-1].residual == pytest.approx(sliced.residual)
    np.testing.assert_array_equal(sliced.positions, whole.positions)
    assert sliced.converged and sliced.iterations == whole.iterations


def test_the_hessian_structure_is_prepared_in_units_and_gives_the_same_fold(monkeypatch: pytest.MonkeyPatch) -> None:
    """``Solver.prepare_steps`` (a Blender job's "model" units): the nested dissection one component at a time,
    then the factorisation's structure, then the scatter indices in units of ``SCATTER_UNIT`` block pairs (one
    call took 40–130 ms at 5,000 faces); the assembler it leaves is the one :attr:`Solver.assembler` makes, and a
    fold with it is bit-identical."""
    from curved_fold.core.solve import newton

    mesh = bisector_mesh()[1]
    plain = Solver(mesh).assembler
    model = plain.model
    pairs = 4 * len(model.bar_k) + 16 * len(model.hinge_k) + 9 * len(model.triangles)
    monkeypatch.setattr(newton, "SCATTER_UNIT", 50)
    solver = Solver(mesh)
    steps = solver.prepare_steps()
    labels = []
    with pytest.raises(StopIteration) as done:
        while True:
            labels.append(next(steps))
    prepared = done.value.value
    first_scatter = labels.index("scatter")
    assert first_scatter > 1 and set(labels[: first_scatter - 1]) == {"ordering"}
    assert labels[first_scatter - 1] == "structure" and set(labels[first_scatter:]) == {"scatter"}
    assert len(labels) - first_scatter >= pairs // 50  # every part in units of at most 50 block pairs
    assert prepared is solver.assembler  # kept, not made again
    assert list(solver.prepare_steps()) == []  # nothing left to do
    assert prepared.matrix.storage_size == plain.matrix.storage_size
    for name in ("bar_index", "hinge_index", "face_index"):
        np.testing.assert_array_equal(getattr(prepared, name), getattr(plain, name))
    np.testing.assert_array_equal(prepared.work["index"], plain.work["index"])
    np.testing.assert_array_equal(solver.solve(0.8).positions, Solver(mesh).solve(0.8).positions)


def test_a_tolerance_below_the_round_off_floor_converges_to_round_off(monkeypatch: pytest.MonkeyPatch) -> None:
    """No representable position is closer to equilibrium than the change one unit in the last place of the
    positions makes to the forces (``newton.roundoff_floor``). Asked for a tolerance below it (0, 1e-16), a fold
    stagnates there; within ``ROUNDOFF_FACTOR`` of the floor it is converged and says so, instead of crawling to the
    budget or stalling. A tolerance it can reach is unaffected."""
    from curved_fold.core.solve import newton

    mesh = grid_mesh(6, 6, 60.0, {(3 + 7 * j, 3 + 7 * (j + 1)): ("V", 150.0) for j in range(6)})
    reachable = Solver(mesh, SolverSettings(tolerance=1e-12)).solve(0.8)
    assert reachable.converged and reachable.message.startswith("converged: residual")
    for tolerance in (1e-16, 0.0):
        r = Solver(mesh, SolverSettings(tolerance=tolerance)).solve(0.8)
        assert r.converged and r.message.startswith("converged to round-off"), r.message
        assert r.residual < 1e-12 and r.negative_pivots == 0
        assert rigid_rms(r.positions, reachable.positions) / mesh.diagonal < 1e-9
    monkeypatch.setattr(newton, "ROUNDOFF_FACTOR", 0.0)
    assert not Solver(mesh, SolverSettings(tolerance=0.0)).solve(0.8).converged


def test_a_path_fold_message_counts_the_whole_path():
    """The message of a fold along the natural path counts the path's iterations, as the report does (the last
    stage's own count read "not converged … after 0 iterations (limit)" beside "500 iterations")."""
    from tests.test_solver_fixtures import fixture_mesh

    mesh = fixture_mesh("Treble_Clef.svg")
    capped = Solver(mesh, SolverSettings(max_iterations=20)).solve(1.0)
    assert capped.iterations == 20 and "after 20 iterations (0 in the last step) (limit)" in capped.message
    done = Solver(mesh).solve(1.0)
    assert f"after {done.iterations} iterations (" in done.message
