"""The nested-dissection multifrontal factorisation (``core/solve/dissection.py``) against dense numpy: solves,
inertia, negative-curvature directions, shifts, odd graphs, both backends (OpenBLAS routines and numpy fallback)."""

from __future__ import annotations

import contextlib

import numpy as np
import pytest

from curved_fold.core.solve import lapack
from curved_fold.core.solve.dissection import NestedDissection, dissect
from curved_fold.core.solve.linalg import _csr
from curved_fold.core.solve.model import build_model
from curved_fold.core.solve.newton import HessianAssembler
from tests.test_forces import grid_mesh

HAS_OPENBLAS = lapack.routines() is not None


def random_matrix(n: int, pairs: np.ndarray, seed: int = 0, spread: float = 0.3):
    """A random symmetric matrix of 3×3 node blocks coupling exactly ``pairs`` (and each node with itself): the
    node blocks ``(rows, cols, blocks)`` as a caller scatters them (each coupling as (i, j) and (j, i)), and the
    same matrix dense."""
    rng = np.random.default_rng(seed)
    up = np.unique(np.sort(np.asarray(pairs).reshape(-1, 2), axis=1), axis=0)
    up = up[up[:, 0] != up[:, 1]]
    m = len(up)
    rows = np.concatenate([up[:, 0], up[:, 1], np.arange(n)])
    cols = np.concatenate([up[:, 1], up[:, 0], np.arange(n)])
    blocks = rng.normal(size=(len(rows), 3, 3))
    blocks[:m] *= spread
    blocks[m : 2 * m] = blocks[:m].transpose(0, 2, 1)
    diag = blocks[2 * m :]
    diag[:] = 0.5 * (diag + diag.transpose(0, 2, 1))
    A = np.zeros((3 * n, 3 * n))
    for r, c, b in zip(rows, cols, blocks, strict=True):
        A[3 * r : 3 * r + 3, 3 * c : 3 * c + 3] += b
    return rows, cols, blocks, A


def storage_of(nd: NestedDissection, rows, cols, blocks) -> np.ndarray:
    return nd.assemble(nd.scatter_index(rows, cols), blocks)


def backend_context(name: str):
    return lapack.disabled() if name == "numpy" else contextlib.nullcontext()


def fixture_model(name: str):
    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.mesh.build import build_mesh
    from curved_fold.core.solve.solver import Solver
    from tests.test_solver_fixtures import FIXTURES

    return Solver(build_mesh(read_pattern(FIXTURES / name), mesh_type="ruling")).model


def check_structure(nd: NestedDissection, pairs: np.ndarray) -> None:
    """The ordering is a permutation in postorder, every boundary lies in ancestors of its supernode, and every
    coupling is in the factor's structure."""
    n = nd.n_nodes
    assert np.array_equal(np.sort(nd.node_order), np.arange(n))
    K = len(nd.supernodes)
    for s in range(K):
        assert nd.parent[s] == -1 or nd.parent[s] > s
        ancestors = set()
        a = nd.parent[s]
        while a >= 0:
            ancestors.add(int(a))
            a = nd.parent[a]
        owners = set(nd.supernode_of[nd.node_order[nd.boundary[s]]].tolist())
        assert owners <= ancestors
        assert nd.first_descendant[s] <= s
    if len(pairs):
        nd.scatter_index(pairs[:, 0], pairs[:, 1])
        nd.scatter_index(pairs[:, 1], pairs[:, 0])


@pytest.mark.parametrize("mesh", ["grid", "fixture"])
def test_solves_equal_dense_solves_on_real_mesh_couplings(backend, mesh):
    """Random SPD matrices with the couplings of a creased grid and of a fixture's ruling mesh (several leaf
    sizes, so small and large supernodes): the factorisation's solves equal ``np.linalg.solve``."""
    if mesh == "grid":
        model = build_model(grid_mesh(8, 8, 80.0, {(4, 13): ("V", 90.0), (13, 22): ("M", -60.0)}))
        leaves = (4, 12, 400)
    else:
        model = fixture_model("Rotating_Star.svg")
        leaves = (8, 32)
    pairs = HessianAssembler.coupling_pairs(model)
    n = model.n_nodes
    rows, cols, blocks, A = random_matrix(n, pairs, seed=1)
    shift = 0.05 - np.linalg.eigvalsh(A)[0]
    M = A + shift * np.eye(3 * n)
    rng = np.random.default_rng(2)
    for leaf, merged in [(leaf, False) for leaf in leaves] + [(leaves[0], True)]:
        nd = NestedDissection(n, pairs, leaf, amalgamate=merged)
        check_structure(nd, pairs)
        storage = storage_of(nd, rows, cols, blocks)
        np.testing.assert_allclose(nd.dense(storage), 0.5 * (A + A.T), rtol=0, atol=1e-12)
        np.testing.assert_array_equal(nd.diagonal(storage), np.diag(A))
        factor = nd.factor(storage, shift, inertia=True)
        assert factor.negative_pivots == 0 and factor.negative_direction() is None
        if backend == "lapack":
            assert all(u is not None for u in factor.chols)
        for _ in range(2):
            rhs = rng.normal(size=3 * n)
            x = factor.apply(rhs)
            np.testing.assert_allclose(x, np.linalg.solve(M, rhs), rtol=0, atol=1e-9 * np.max(np.abs(x)))
    assert len(NestedDissection(n, pairs, 4, amalgamate=False).supernodes) > 10  # really dissected


def indefinite_grid():
    """A random symmetric matrix with the couplings of an 8×8 grid's model and its dissection (leaves of 6 nodes,
    not merged): ``(n, nd, storage, A, eigenvalues of A)``; shifted below its middle it has negative pivots in
    leaves, inner separators and the root."""
    model = build_model(grid_mesh(8, 8, 80.0))
    pairs = HessianAssembler.coupling_pairs(model)
    n = model.n_nodes
    rows, cols, blocks, A = random_matrix(n, pairs, seed=3)
    nd = NestedDissection(n, pairs, 6, amalgamate=False)
    return n, nd, storage_of(nd, rows, cols, blocks), A, np.linalg.eigvalsh(A)


def test_inertia_and_negative_direction_on_indefinite_matrices(backend):
    """Indefinite matrices (negative pivots in leaves, in inner separators and at the root): the count of negative
    pivots is the count of negative eigenvalues (Sylvester), and ``w = L⁻ᵀ z`` has ``wᵀ A w`` = the lowest pivot
    eigenvalue, reaching into the subtree of that pivot's supernode and nowhere else."""
    n, nd, storage, A, lam = indefinite_grid()
    for shift in (-lam[0] - 0.3 * (lam[-1] - lam[0]), -lam[0] - 0.03 * (lam[-1] - lam[0]), 0.0):
        M = A + shift * np.eye(3 * n)
        negatives = int(np.sum(np.linalg.eigvalsh(M) < 0))
        assert negatives > 0
        factor = nd.factor(storage, shift, inertia=True)
        assert factor.negative_pivots == negatives
        value, k, z = factor.lowest_pivot
        w = factor.negative_direction()
        assert w is not None and value < 0
        assert w @ M @ w == pytest.approx(value * float(z @ z), rel=1e-8)
        dof_owner = np.repeat(nd.supernode_of, 3)
        inside = (dof_owner >= nd.first_descendant[k]) & (dof_owner <= k)
        assert not np.any(w[~inside])  # zero outside the subtree of k
        rhs = np.random.default_rng(4).normal(size=3 * n)
        x = factor.apply(rhs)
        np.testing.assert_allclose(x, np.linalg.solve(M, rhs), rtol=0, atol=1e-8 * np.max(np.abs(x)))
        plain = nd.factor(storage, shift)  # not counting: an indefinite pivot makes it start again, keeping pivots
        assert plain.negative_pivots is None
        np.testing.assert_allclose(plain.apply(rhs), x, rtol=0, atol=1e-10 * np.max(np.abs(x)))


def test_definite_only_stops_at_the_first_indefinite_pivot(backend):
    """``definite_only``: an indefinite matrix is reported (≥ 1 negative pivot, incomplete) without finishing the
    elimination; a positive definite one is factored exactly as without it."""
    n, nd, storage, A, lam = indefinite_grid()
    indefinite = -lam[0] - 0.3 * (lam[-1] - lam[0])
    assert nd.factor(storage, indefinite, inertia=True).negative_pivots > 1
    stopped = nd.factor(storage, indefinite, inertia=True, definite_only=True)
    assert stopped.negative_pivots == 1 and not stopped.complete
    assert sum(c is not None for c in stopped.chols) + sum(v is not None for v in stopped.inverses) < len(
        nd.supernodes
    )  # not every pivot was factored
    definite = -lam[0] + 0.1 * (lam[-1] - lam[0])
    spd = nd.factor(storage, definite, inertia=True, definite_only=True)
    assert spd.negative_pivots == 0 and spd.complete
    rhs = np.random.default_rng(5).normal(size=3 * n)
    np.testing.assert_array_equal(spd.apply(rhs), nd.factor(storage, definite, inertia=True).apply(rhs))


def test_negative_subspace_direction_combines_every_negative_mode(backend):
    """``negative_subspace_direction``: ``w = L⁻ᵀ z`` with ``z`` every negative pivot eigenvector, weighted
    ``λ/λ_min`` and signed by the chooser: ``wᵀ A w = Σ c² λ`` (exact, by congruence), more negative than the one
    lowest mode's ``λ_min``; the eigenvectors' own signs do not matter."""
    n, nd, storage, A, lam = indefinite_grid()
    shift = -lam[0] - 0.3 * (lam[-1] - lam[0])
    M = A + shift * np.eye(3 * n)
    factor = nd.factor(storage, shift, inertia=True)
    assert sum(len(vals) for _, vals, _ in factor.negative_pairs) == factor.negative_pivots > 1
    assert len({k for k, _, _ in factor.negative_pairs}) > 1  # negative pivots in several supernodes
    chooser = np.cos(np.arange(3 * n) * 2.4 + 0.5)
    w = factor.negative_subspace_direction(chooser)
    lowest = factor.lowest_pivot[0]
    expected = sum(float(np.sum((vals / lowest) ** 2 * vals)) for _, vals, _ in factor.negative_pairs)
    assert w @ M @ w == pytest.approx(expected, rel=1e-9)
    assert expected < lowest < 0
    factor.negative_pairs = [(k, vals, -vecs) for k, vals, vecs in factor.negative_pairs]
    np.testing.assert_allclose(factor.negative_subspace_direction(chooser), w, rtol=0, atol=1e-12 * np.abs(w).max())
    assert nd.factor(storage, -lam[0] + 1.0, inertia=True).negative_subspace_direction(chooser) is None


def test_negative_direction_back_substitutes_through_the_subtree(backend):
    """A single negative pivot placed on an inner separator (not a leaf, not the root): its direction is nonzero
    on descendants (the back substitution through ``X_s`` reaches them), and ``wᵀ A w`` is its eigenvalue."""
    model = build_model(grid_mesh(10, 10, 80.0))
    pairs = HessianAssembler.coupling_pairs(model)
    n = model.n_nodes
    rows, cols, blocks, A = random_matrix(n, pairs, seed=5, spread=0.1)
    nd = NestedDissection(n, pairs, 6, amalgamate=False)
    inner = [s for s in range(len(nd.supernodes)) if nd.children[s] and nd.parent[s] >= 0]
    k = max(inner, key=lambda s: s - nd.first_descendant[s])
    node = nd.supernodes[k][0]
    shift = 2.0 - np.linalg.eigvalsh(A)[0]
    M = A + shift * np.eye(3 * n)
    M[3 * node, 3 * node] -= 1e3  # one strongly negative direction
    diag_blocks = blocks[len(blocks) - n :]
    diag_blocks[node, 0, 0] -= 1e3
    storage = storage_of(nd, rows, cols, blocks)
    factor = nd.factor(storage, shift, inertia=True)
    assert factor.negative_pivots == int(np.sum(np.linalg.eigvalsh(M) < 0)) == 1
    value, where, z = factor.lowest_pivot
    assert where == k
    w = factor.negative_direction()
    assert w @ M @ w == pytest.approx(value, rel=1e-9)
    dof_owner = np.repeat(nd.supernode_of, 3)
    assert np.any(w[dof_owner < k])  # reached the descendants
    assert not np.any(w[dof_owner > k])


def test_vector_shift_with_huge_and_infinite_entries(backend):
    """Pinned degrees of freedom get a shift of 1e12·scale (the solver's pins) or +inf: their unknowns vanish
    (exactly 0 for +inf) and the others solve the matrix without them."""
    model = build_model(grid_mesh(6, 6, 80.0))
    pairs = HessianAssembler.coupling_pairs(model)
    n = model.n_nodes
    rows, cols, blocks, A = random_matrix(n, pairs, seed=6)
    base = 0.5 - np.linalg.eigvalsh(A)[0]
    nd = NestedDissection(n, pairs, 5, amalgamate=False)
    storage = storage_of(nd, rows, cols, blocks)
    rng = np.random.default_rng(7)
    pinned = rng.choice(3 * n, size=3 * n // 5, replace=False)
    keep = np.setdiff1d(np.arange(3 * n), pinned)
    rhs = rng.normal(size=3 * n)
    reduced = np.linalg.solve((A + base * np.eye(3 * n))[np.ix_(keep, keep)], rhs[keep])
    scale = float(np.max(np.abs(A)))
    for big in (1e12 * scale, np.inf):
        shift = np.full(3 * n, base)
        shift[pinned] += big
        factor = nd.factor(storage, shift, inertia=True)
        x = factor.apply(rhs)
        assert factor.negative_pivots == 0
        assert np.max(np.abs(x[pinned])) <= (0.0 if np.isinf(big) else 1e-10)
        np.testing.assert_allclose(x[keep], reduced, rtol=0, atol=1e-9 * np.max(np.abs(reduced)))


@pytest.mark.parametrize(
    "graph",
    ["one node", "two nodes", "three nodes", "isolated nodes", "disconnected", "chain", "star", "complete", "random"],
)
def test_odd_graphs(backend, graph):
    """Tiny graphs, isolated nodes, several components, a long chain, a star, a clique and a random non-planar
    graph: a valid ordering (every coupling in the structure) and exact solves."""
    rng = np.random.default_rng(8)
    if graph == "one node":
        n, pairs = 1, np.zeros((0, 2), dtype=np.int64)
    elif graph == "two nodes":
        n, pairs = 2, np.array([[0, 1]])
    elif graph == "three nodes":
        n, pairs = 3, np.array([[0, 1], [1, 2]])
    elif graph == "isolated nodes":
        n, pairs = 40, np.array([[3, 4], [10, 11], [11, 12]])
    elif graph == "disconnected":
        a = HessianAssembler.coupling_pairs(build_model(grid_mesh(5, 5)))
        b = HessianAssembler.coupling_pairs(build_model(grid_mesh(3, 4)))
        n = 36 + 20 + 7  # two grids and 7 isolated nodes
        pairs = np.concatenate([a, b + 36])
    elif graph == "chain":
        n = 300
        pairs = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    elif graph == "star":
        n = 50
        pairs = np.column_stack([np.zeros(n - 1, dtype=np.int64), np.arange(1, n)])
    elif graph == "complete":
        n = 30
        pairs = np.array([[i, j] for i in range(n) for j in range(i + 1, n)])
    else:
        n = 200
        pairs = rng.integers(0, n, size=(500, 2))
    nd = NestedDissection(n, pairs, 8, amalgamate=False)
    check_structure(nd, np.asarray(pairs).reshape(-1, 2))
    check_structure(NestedDissection(n, pairs, 8), np.asarray(pairs).reshape(-1, 2))
    rows, cols, blocks, A = random_matrix(n, pairs, seed=9)
    shift = 0.1 - np.linalg.eigvalsh(A)[0]
    M = A + shift * np.eye(3 * n)
    storage = storage_of(nd, rows, cols, blocks)
    rhs = rng.normal(size=3 * n)
    x = nd.factor(storage, shift, inertia=True).apply(rhs)
    np.testing.assert_allclose(x, np.linalg.solve(M, rhs), rtol=0, atol=1e-9 * np.max(np.abs(x)))
    negatives = int(np.sum(np.linalg.eigvalsh(A) < 0))
    if negatives:  # unshifted: indefinite
        factor = nd.factor(storage, 0.0, inertia=True)
        assert factor.negative_pivots == negatives
    if graph == "random":
        kinds = {plan[0][0] for plan in nd._extend if plan is not None}
        assert "flat" in kinds  # many runs: the scatter form of the extend-add is exercised too
    if graph == "isolated nodes":
        assert len(nd.supernodes) <= 6  # small components are grouped into leaves, not one supernode each


def circles_in_a_square_svg(rings: int = 4, size: float = 100.0) -> str:
    """Concentric circular creases (M and V in turn) in a square sheet: the constrained Delaunay triangulation fans
    the region between the square and the outer circle from the square's corners."""
    c = size / 2
    paths = "".join(
        f'<path d="M {c + r:g} {c:g} A {r:g} {r:g} 0 1 0 {c - r:g} {c:g} A {r:g} {r:g} 0 1 0 {c + r:g} {c:g} Z" '
        f'fill="none" stroke="{"#ff0000" if k % 2 == 0 else "#0000ff"}" opacity="0.5"/>'
        for k, r in enumerate(np.linspace(0.12 * size, 0.42 * size, rings))
    )
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{size:g}mm" height="{size:g}mm" '
        f'viewBox="0 0 {size:g} {size:g}"><rect x="0" y="0" width="{size:g}" height="{size:g}" fill="none" '
        f'stroke="#000000"/>{paths}</svg>'
    )


def test_fan_hubs_are_ordered_last_and_keep_the_separators_small(backend, tmp_path, monkeypatch):
    """A node coupled to far more nodes than the median one (a corner fanned to the outer circle) is the root
    supernode, and the rest is dissected without it: through the hub every node was two steps from every other,
    the BFS levels swelled and so did the separators (≥ 5× the flops here, 37× at 5,902 faces). Solves still equal
    dense ones."""
    from curved_fold.core.io.reader import read_pattern
    from curved_fold.core.mesh.build import build_mesh
    from curved_fold.core.solve import dissection

    svg = tmp_path / "circles.svg"
    svg.write_text(circles_in_a_square_svg())
    model = build_model(build_mesh(read_pattern(svg)))
    pairs = HessianAssembler.coupling_pairs(model)
    n = model.n_nodes
    indptr, _ = _csr(n, pairs)
    degree = np.diff(indptr)
    hubs = dissection.dense_nodes(indptr)
    assert len(hubs) and np.all(degree[hubs] > 3 * np.median(degree))
    nd = NestedDissection(n, pairs)
    check_structure(nd, pairs)
    assert set(np.concatenate([nd.supernodes[s] for s in range(len(nd.supernodes)) if nd.parent[s] == -1])) >= set(
        hubs.tolist()
    )
    monkeypatch.setattr(dissection, "DENSE_FACTOR", float("inf"))
    through_hubs = NestedDissection(n, pairs)
    assert nd.flops() * 5 <= through_hubs.flops()
    rows, cols, blocks, A = random_matrix(n, pairs, seed=3)
    shift = 0.05 - np.linalg.eigvalsh(A)[0]
    factor = nd.factor(storage_of(nd, rows, cols, blocks), shift, inertia=True)
    assert factor.negative_pivots == 0
    rhs = np.random.default_rng(4).normal(size=3 * n)
    x = factor.apply(rhs)
    np.testing.assert_allclose(x, np.linalg.solve(A + shift * np.eye(3 * n), rhs), atol=1e-9 * np.max(np.abs(x)))


def test_dissection_separates_and_stays_in_leaf_size():
    """On a 30×30 grid the top separator is a small fraction of the nodes, the tree is balanced and the parts
    not dissected further are at most the leaf size; the flop count is far below the block-tridiagonal one."""
    from curved_fold.core.solve.linalg import BlockTridiagonal

    model = build_model(grid_mesh(30, 30))
    pairs = HessianAssembler.coupling_pairs(model)
    n = model.n_nodes
    indptr, indices = _csr(n, pairs)
    sets, parent = dissect(n, indptr, indices, 24)
    assert len(sets[0]) <= 3 * 31  # the first separator: about one grid line (wing couplings make it thicker)
    nd = NestedDissection(n, pairs, 24, amalgamate=False)
    leaves = [s for s in range(len(nd.supernodes)) if not nd.children[s]]
    assert max(len(nd.supernodes[s]) for s in leaves) <= 24
    bt = BlockTridiagonal(n, pairs, 24)
    s = bt.sizes.astype(float)
    nxt = np.append(s[1:], 0)
    band = float(np.sum(s**3 / 3 + s * s * nxt + s * nxt * nxt))
    assert nd.flops() < 0.5 * band


def test_couplings_outside_the_structure_are_refused():
    model = build_model(grid_mesh(6, 6))
    pairs = HessianAssembler.coupling_pairs(model)
    nd = NestedDissection(model.n_nodes, pairs, 6, amalgamate=False)
    leaves = [s for s in range(len(nd.supernodes)) if not nd.children[s]]
    a, b = nd.supernodes[leaves[0]][0], nd.supernodes[leaves[-1]][0]  # two leaves never share a front
    for rows, cols in (([a], [b]), ([b], [a]), ([a, a], [a, b])):
        with pytest.raises(ValueError, match="outside"):
            nd.scatter_index(np.array(rows), np.array(cols))


@pytest.mark.parametrize("where", ["pivot", "coupling", "shift"])
def test_non_finite_and_singular_raise(backend, where):
    model = build_model(grid_mesh(5, 5))
    pairs = HessianAssembler.coupling_pairs(model)
    n = model.n_nodes
    rows, cols, blocks, A = random_matrix(n, pairs, seed=10)
    nd = NestedDissection(n, pairs, 5, amalgamate=False)
    storage = storage_of(nd, rows, cols, blocks)
    shift = np.full(3 * n, 1.0 - np.linalg.eigvalsh(A)[0])
    s = 0  # a leaf: its pivot and coupling are the first entries of the storage
    p, b = int(nd.pivot_size[s]), int(nd.boundary_size[s])
    assert b > 0
    if where == "pivot":
        storage[1] = np.nan
    elif where == "coupling":
        storage[p * p + nd.zero_rows[s] * b + 2] = np.nan  # a row coupled to the boundary (the ones above are 0)
    else:
        shift[nd.order[3 * nd.start[-1]]] = np.nan  # in the root's pivot
    with pytest.raises(np.linalg.LinAlgError):
        nd.factor(storage, shift)
    with pytest.raises(np.linalg.LinAlgError):
        nd.factor(np.zeros(nd.storage_size + 1), 0.0, inertia=True)


@pytest.mark.skipif(not HAS_OPENBLAS, reason="numpy's OpenBLAS not found")
def test_wrappers_take_blocks_of_rows():
    """The factorisation hands ``potrf``/``trsm``/``syrk``/``trsv`` blocks of bigger arrays (``S[k:, k:]``, ``C[k:]``):
    the leading dimension comes from the strides, and a block whose rows are not contiguous is refused."""
    lib = lapack.routines()
    rng = np.random.default_rng(11)
    big = rng.normal(size=(12, 12))
    big = big @ big.T + 12 * np.eye(12)
    S = big[3:10, 3:10]  # rows of stride 12
    U = np.array(S)
    assert lib.cholesky(S)
    np.testing.assert_allclose(np.triu(S), np.linalg.cholesky(U).T, rtol=0, atol=1e-12)
    B = rng.normal(size=(7, 9))
    W = np.zeros((7, 15))
    W[:, 2:11] = B
    lib.solve_upper_transposed(S, W[:, 2:11])
    np.testing.assert_allclose(np.triu(S).T @ W[:, 2:11], B, atol=1e-12)
    C = np.zeros((20, 20))
    lib.subtract_gram(C[5:14, 5:14], W[:, 2:11])
    np.testing.assert_allclose(np.triu(C[5:14, 5:14]), np.triu(-B.T @ np.linalg.inv(U) @ B), atol=1e-10)
    x = rng.normal(size=7)
    y = x.copy()
    lib.solve_upper_vector(S, y)
    np.testing.assert_allclose(np.triu(S) @ y, x, atol=1e-12)
    with pytest.raises(ValueError):
        lib.cholesky(big[::2, ::2])


def test_backends_agree_on_a_real_fixture_hessian():
    """The assembled exact Hessian of a fixture at a perturbed state (indefinite): same inertia and solves with
    either backend, equal to the dense solve."""
    if not HAS_OPENBLAS:
        pytest.skip("numpy's OpenBLAS not found")
    from curved_fold.core.solve import forces as F  # noqa: N812

    model = fixture_model("curvedPleatSimple.svg")
    x = model.rest + np.random.default_rng(12).normal(0, 0.01, model.rest.shape)
    ev = F.evaluate(model, x, F.fold_angles(model, x), 0.8, jacobians=True)
    assembler = HessianAssembler(model, NestedDissection(model.n_nodes, HessianAssembler.coupling_pairs(model), 8))
    H = assembler.assemble_exact(x, ev)
    A = assembler.matrix.dense(H)
    lowest = np.linalg.eigvalsh(A)[0]
    assert lowest < 0
    rhs = np.random.default_rng(13).normal(size=A.shape[0])
    shift = 0.5 * abs(lowest)
    M = A + shift * np.eye(A.shape[0])
    expected = np.linalg.solve(M, rhs)
    negatives = int(np.sum(np.linalg.eigvalsh(M) < 0))
    got = {}
    for name in ("lapack", "numpy"):
        with backend_context(name):
            factor = assembler.matrix.factor(H, shift, inertia=True)
            got[name] = factor.apply(rhs)
        assert factor.negative_pivots == negatives
        np.testing.assert_allclose(got[name], expected, rtol=0, atol=1e-8 * np.max(np.abs(expected)))
    np.testing.assert_allclose(got["lapack"], got["numpy"], rtol=0, atol=1e-9 * np.max(np.abs(expected)))


def test_amalgamation_merges_where_the_cost_model_gains():
    """On a fixture's ruling mesh, merging children into their parents (:func:`dissection._amalgamate`) leaves
    fewer supernodes, a valid structure, a lower modelled time, and a solve equal to the unmerged one."""
    from curved_fold.core.solve.dissection import _time

    model = fixture_model("Rotating_Star.svg")
    pairs = HessianAssembler.coupling_pairs(model)
    n = model.n_nodes
    plain = NestedDissection(n, pairs, 8, amalgamate=False)
    merged = NestedDissection(n, pairs, 8)
    check_structure(merged, pairs)
    assert 1 < len(merged.supernodes) < len(plain.supernodes)

    def modelled(nd):
        return sum(_time(int(p), int(b)) for p, b in zip(nd.pivot_size, nd.boundary_size, strict=True))

    assert modelled(merged) < modelled(plain)
    rows, cols, blocks, A = random_matrix(n, pairs, seed=14)
    shift = 0.1 - np.linalg.eigvalsh(A)[0]
    rhs = np.random.default_rng(15).normal(size=3 * n)
    x = [nd.factor(storage_of(nd, rows, cols, blocks), shift).apply(rhs) for nd in (plain, merged)]
    np.testing.assert_allclose(x[1], x[0], rtol=0, atol=1e-10 * np.max(np.abs(x[0])))
