"""The block factorisation with numpy's OpenBLAS (Cholesky pivots, ``core/solve/lapack.py``) and without it (the
numpy fallback, inverse pivots): the same solves, inertia and negative-curvature directions, on random and on real
assembled Hessians."""

from __future__ import annotations

import contextlib

import numpy as np
import pytest

from curved_fold.core.solve import forces as F  # noqa: N812
from curved_fold.core.solve import lapack
from curved_fold.core.solve.dissection import NestedDissection
from curved_fold.core.solve.linalg import BlockTridiagonal, _blas_control, single_threaded_blas
from curved_fold.core.solve.model import build_model
from curved_fold.core.solve.newton import HessianAssembler
from curved_fold.core.solve.solver import Solver, SolverSettings, rigid_rms
from tests.test_forces import grid_mesh
from tests.test_solver_tail import dense

HAS_OPENBLAS = lapack.routines() is not None


def chain(n: int = 60, min_block: int = 4, seed: int = 0, spread: float = 0.3):
    """A block-tridiagonal matrix on a chain of n nodes (couplings to the next two): the ordering, its storage and
    the same matrix dense. Diagonal node blocks symmetric + 4 I, off-diagonal ones ``spread``-scaled normals."""
    rng = np.random.default_rng(seed)
    pairs = np.array([[i, i + 1] for i in range(n - 1)] + [[i, i + 2] for i in range(n - 2)])
    bt = BlockTridiagonal(n, pairs, min_block=min_block)
    rows = np.concatenate([pairs[:, 0], pairs[:, 1], np.arange(n)])
    cols = np.concatenate([pairs[:, 1], pairs[:, 0], np.arange(n)])
    blocks = rng.normal(size=(len(rows), 3, 3))
    blocks[: len(pairs)] *= spread
    blocks[len(pairs) : 2 * len(pairs)] = blocks[: len(pairs)].transpose(0, 2, 1)
    diag = blocks[2 * len(pairs) :]
    diag[:] = 0.5 * (diag + diag.transpose(0, 2, 1)) + 4.0 * np.eye(3)
    A = np.zeros((3 * n, 3 * n))
    for r, c, b in zip(rows, cols, blocks, strict=True):
        A[3 * r : 3 * r + 3, 3 * c : 3 * c + 3] += b
    return bt, rows, cols, blocks, A


def storage_of(bt, rows, cols, blocks):
    return bt.assemble(bt.scatter_index(rows, cols), blocks)


def test_openblas_is_found_with_its_routines_where_numpy_bundles_it():
    """numpy's wheels bundle OpenBLAS (numpy 1.x ``libopenblas64_``, numpy 2.x ``libscipy_openblas64_``): the four
    routines and the thread control are found, and single_threaded_blas sets one thread and restores the count."""
    if not lapack._candidates():
        pytest.skip("this numpy bundles no OpenBLAS")
    found = lapack.openblas()
    assert found is not None and found.has_lapack, lapack._candidates()
    assert HAS_OPENBLAS
    get, set_ = _blas_control()
    before = int(get())
    with single_threaded_blas():
        assert int(get()) == 1
    assert int(get()) == before


@pytest.mark.skipif(not HAS_OPENBLAS, reason="numpy's OpenBLAS not found")
def test_wrappers_match_numpy():
    lib = lapack.routines()
    rng = np.random.default_rng(5)
    n, m = 9, 4
    M = rng.normal(size=(n, n))
    S = M @ M.T + n * np.eye(n)
    U = S.copy()
    assert lib.cholesky(U)
    np.testing.assert_allclose(np.triu(U), np.linalg.cholesky(S).T, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(np.tril(U, -1), np.tril(S, -1))  # the other triangle is not touched
    B = rng.normal(size=(n, m))
    W = B.copy()
    lib.solve_upper_transposed(U, W)
    np.testing.assert_allclose(np.triu(U).T @ W, B, atol=1e-12)
    C = rng.normal(size=(m, m))
    C = C + C.T
    C2 = C.copy()
    lib.subtract_gram(C2, W)
    np.testing.assert_allclose(np.triu(C2), np.triu(C - W.T @ W), atol=1e-12)
    np.testing.assert_array_equal(np.tril(C2, -1), np.tril(C, -1))
    x = rng.normal(size=n)
    y = x.copy()
    lib.solve_upper_vector(U, y)
    np.testing.assert_allclose(np.triu(U) @ y, x, atol=1e-12)
    y = x.copy()
    lib.solve_upper_vector(U, y, transpose=True)
    np.testing.assert_allclose(np.triu(U).T @ y, x, atol=1e-12)
    assert not lib.cholesky(-S)  # not positive definite: info > 0
    with pytest.raises(ValueError):
        lib.cholesky(np.asfortranarray(rng.normal(size=(3, 4))))
    with pytest.raises(ValueError):
        lib.solve_upper_vector(U, x[::2].copy())


@pytest.mark.parametrize("shift_kind", ["scalar", "vector"])
def test_factor_and_apply_solve_a_random_spd_block_tridiagonal_matrix(backend, shift_kind):
    bt, rows, cols, blocks, A = chain(80, min_block=5, seed=1)
    storage = storage_of(bt, rows, cols, blocks)
    rng = np.random.default_rng(2)
    shift = 3.0 if shift_kind == "scalar" else rng.uniform(2.5, 4.0, 3 * bt.n_nodes)
    M = A + np.diag(np.broadcast_to(shift, (3 * bt.n_nodes,)))
    assert np.linalg.eigvalsh(M)[0] > 0
    factor = bt.factor(storage, shift, inertia=True)
    assert factor.negative_pivots == 0 and factor.negative_direction() is None
    if backend == "lapack":
        assert all(c is not None for c in factor.chols)  # every pivot by Cholesky
    for _ in range(3):
        rhs = rng.normal(size=3 * bt.n_nodes)
        x = factor.apply(rhs)
        np.testing.assert_allclose(x, np.linalg.solve(M, rhs), rtol=0, atol=1e-11 * np.max(np.abs(x)))
    np.testing.assert_allclose(bt.solve(storage, rhs, shift), x, rtol=0, atol=1e-13 * np.max(np.abs(x)))


def test_backends_agree_to_round_off_on_a_real_exact_hessian():
    """The exact Hessian of a creased, perturbed grid (indefinite away from equilibrium) with and without the
    OpenBLAS routines: the same inertia, solves equal to the dense solve and to each other to round-off."""
    if not HAS_OPENBLAS:
        pytest.skip("numpy's OpenBLAS not found")
    mesh = grid_mesh(8, 8, 80.0, {(4, 13): ("V", 90.0), (13, 22): ("V", 90.0), (22, 31): ("M", -60.0)})
    model = build_model(mesh)
    x = model.rest + np.random.default_rng(7).normal(0, 0.05, model.rest.shape)
    theta = F.fold_angles(model, x)
    ev = F.evaluate(model, x, theta, 0.8, jacobians=True)
    assembler = HessianAssembler(model, NestedDissection(model.n_nodes, HessianAssembler.coupling_pairs(model), 6))
    H = assembler.assemble_exact(x, ev)
    A = dense(assembler, H)
    lowest = np.linalg.eigvalsh(A)[0]
    rhs = np.random.default_rng(8).normal(size=A.shape[0])
    out = {}
    for shift in (1e-3 - lowest, 0.5 * abs(lowest)):  # positive definite, then indefinite
        M = A + shift * np.eye(A.shape[0])
        expected = np.linalg.solve(M, rhs)
        negatives = int(np.sum(np.linalg.eigvalsh(M) < 0))
        for name in ("lapack", "numpy"):
            with contextlib_backend(name):
                factor = assembler.matrix.factor(H, shift, inertia=True)
                got = factor.apply(rhs)
            assert factor.negative_pivots == negatives
            np.testing.assert_allclose(got, expected, rtol=0, atol=1e-8 * np.max(np.abs(expected)))
            out[name, shift] = got
            if negatives:
                w = factor.negative_direction()
                assert w is not None and w @ M @ w < 0
                assert w @ M @ w == pytest.approx(factor.lowest_pivot[0], rel=1e-6)  # zᵀ S_k z, |z| = 1
        np.testing.assert_allclose(
            out["lapack", shift], out["numpy", shift], rtol=0, atol=1e-9 * np.max(np.abs(expected))
        )
    assert lowest < 0  # the unshifted Hessian is indefinite, so the second shift tests the inverse pivots


def contextlib_backend(name: str):
    """The numpy fallback forced for ``"numpy"``, the OpenBLAS routines otherwise."""
    return lapack.disabled() if name == "numpy" else contextlib.nullcontext()


def test_inertia_and_negative_direction_with_mixed_pivots(backend):
    """Negative pivots in a middle block and in the last one, positive definite ones around them (the OpenBLAS
    path mixes Cholesky and inverse pivots): the inertia is exact (Sylvester) and wᵀAw = λ_min(S_k) < 0 through
    the blocks before it."""
    bt, rows, cols, blocks, A = chain(60, min_block=4, seed=3)
    n = bt.n_nodes
    diag = blocks[len(blocks) - n :]
    middle = bt.blocks[len(bt.blocks) // 2]
    diag[middle[0]] -= 10.0 * np.eye(3)
    diag[bt.blocks[-1][0], 0, 0] -= 9.0
    A[3 * middle[0] : 3 * middle[0] + 3, 3 * middle[0] : 3 * middle[0] + 3] -= 10.0 * np.eye(3)
    last = bt.blocks[-1][0]
    A[3 * last, 3 * last] -= 9.0
    storage = storage_of(bt, rows, cols, blocks)
    factor = bt.factor(storage, 0.0, inertia=True)
    assert factor.negative_pivots == int(np.sum(np.linalg.eigvalsh(A) < 0)) >= 3
    if backend == "lapack":
        kinds = [c is not None for c in factor.chols]
        assert any(kinds) and not all(kinds)
    w = factor.negative_direction()
    assert w is not None and w @ A @ w < 0
    value, k, z = factor.lowest_pivot
    assert k > 0 and np.any(w[np.concatenate(bt.dofs[:k])])  # back-substituted through the blocks before k
    assert w @ A @ w == pytest.approx(value * float(z @ z), rel=1e-9)
    rhs = np.random.default_rng(4).normal(size=3 * n)
    np.testing.assert_allclose(factor.apply(rhs), np.linalg.solve(A, rhs), rtol=0, atol=1e-9)
    spd = bt.factor(storage, 12.0, inertia=True)
    assert spd.negative_pivots == 0 and spd.negative_direction() is None
    assert bt.factor(storage, 0.0).negative_pivots is None  # not counted unless asked


def test_definite_only_stops_at_the_first_indefinite_pivot(backend):
    """``definite_only``: an indefinite matrix is reported (≥ 1 negative pivot, incomplete, no solve) without the
    eigenvalues and inverses of the later pivots; a positive definite one is factored exactly as without it."""
    bt, rows, cols, blocks, A = chain(60, min_block=4, seed=3)
    n = bt.n_nodes
    diag = blocks[len(blocks) - n :]
    middle = bt.blocks[len(bt.blocks) // 2]
    diag[middle[0]] -= 10.0 * np.eye(3)
    storage = storage_of(bt, rows, cols, blocks)
    assert bt.factor(storage, 0.0, inertia=True).negative_pivots >= 3
    stopped = bt.factor(storage, 0.0, inertia=True, definite_only=True)
    assert stopped.negative_pivots == 1 and not stopped.complete
    assert len(stopped.couplings) == len(bt.blocks) // 2  # the blocks before the indefinite one, nothing after
    spd = bt.factor(storage, 12.0, inertia=True, definite_only=True)
    assert spd.negative_pivots == 0 and spd.complete
    rhs = np.random.default_rng(5).normal(size=3 * n)
    np.testing.assert_array_equal(spd.apply(rhs), bt.factor(storage, 12.0, inertia=True).apply(rhs))


@pytest.mark.parametrize("where", ["first", "later", "coupling", "shift"])
def test_non_finite_blocks_raise(backend, where):
    bt, rows, cols, blocks, A = chain(30, min_block=4, seed=6)
    storage = storage_of(bt, rows, cols, blocks)
    shift = np.full(3 * bt.n_nodes, 1.0)
    if where == "first":
        storage[bt.diag_offset[0] + 1] = np.nan
    elif where == "later":
        storage[bt.diag_offset[2] + 1] = np.nan
    elif where == "coupling":
        storage[bt.sub_offset[1] + 3] = np.nan
    else:
        shift[bt.dofs[-1][0]] = np.nan
    with pytest.raises(np.linalg.LinAlgError):
        bt.factor(storage, shift)


def test_an_infinitely_stiff_degree_of_freedom_gets_zero_with_either_backend(backend):
    """+inf on the diagonal (as today's inverse treats it: that unknown is 0, the others solve the rest)."""
    bt, rows, cols, blocks, A = chain(30, min_block=4, seed=6)
    storage = storage_of(bt, rows, cols, blocks)
    dof = bt.dofs[2][0]
    storage[bt.diag_offset[2]] = np.inf
    rhs = np.random.default_rng(9).normal(size=3 * bt.n_nodes)
    x = bt.factor(storage, 1.0).apply(rhs)
    keep = np.arange(3 * bt.n_nodes) != dof
    M = (A + np.eye(3 * bt.n_nodes))[np.ix_(keep, keep)]
    assert x[dof] == 0.0
    np.testing.assert_allclose(x[keep], np.linalg.solve(M, rhs[keep]), rtol=0, atol=1e-10)


def test_singular_block_raises(backend):
    bt, rows, cols, blocks, A = chain(30, min_block=4, seed=6)
    storage = np.zeros(bt.storage_size + 1)
    with pytest.raises(np.linalg.LinAlgError):
        bt.factor(storage, 0.0)
    with pytest.raises(np.linalg.LinAlgError):
        bt.factor(storage, 0.0, inertia=True)


def test_a_solve_takes_the_same_path_with_either_backend():
    """A fold of a creased grid with the exact tail: the same iterations and energy (12 digits) either way."""
    if not HAS_OPENBLAS:
        pytest.skip("numpy's OpenBLAS not found")
    mesh = grid_mesh(8, 8, 80.0, {(4, 13): ("V", 90.0), (13, 22): ("V", 90.0), (22, 31): ("V", 90.0)})
    results = {}
    for name in ("lapack", "numpy"):
        with contextlib_backend(name):
            results[name] = Solver(mesh, SolverSettings()).solve(0.9)
    a, b = results["lapack"], results["numpy"]
    assert a.converged and b.converged
    assert a.iterations == b.iterations and a.exact_iterations == b.exact_iterations
    assert a.energy == pytest.approx(b.energy, rel=1e-12)
    assert a.negative_pivots == b.negative_pivots == 0
    # the same state up to round-off in the free rigid-body modes (the shift only damps them)
    assert rigid_rms(a.positions, b.positions) < 1e-6  # mm, on an 80 mm sheet
