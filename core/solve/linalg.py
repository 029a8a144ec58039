"""Sparse symmetric linear solves with numpy only: level-set ordering + block-tridiagonal dense elimination.

Stock Blender ships numpy but not scipy, so the Newton solver cannot use a sparse Cholesky. A folded-sheet
Hessian is sparse with a 2D neighbourhood structure, so we order the nodes by breadth-first *levels* of their
coupling graph (nodes coupled by a bar, a triangle or a hinge's two wings). Couplings then join only nodes in the
same or in adjacent levels, and the matrix is **block tridiagonal** with blocks of about √n nodes (the bandwidth of
a reverse-Cuthill–McKee ordering). Consecutive levels are merged into blocks of at least ``min_block`` nodes so
that every block operation is one dense LAPACK/BLAS call; elimination is block Thomas (``N · b²`` flops instead of
``N³``). The ordering and the scatter indices are computed once per mesh; each Newton iteration is then one
``bincount`` (assembly) and ``2·#blocks`` dense calls (solve).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import numpy as np

from . import lapack


def _blas_control() -> tuple:
    """``(get, set)`` thread-count functions of the OpenBLAS that numpy loaded, or ``()`` if none is found.

    numpy's wheels bundle OpenBLAS in ``numpy.libs`` (see :mod:`.lapack`, which finds it under both of numpy's
    naming schemes); this is what ``threadpoolctl`` does, without the dependency.
    """
    found = lapack.openblas()
    return () if found is None else (found.get_threads, found.set_threads)


@contextlib.contextmanager
def single_threaded_blas() -> Iterator[None]:
    """Run the block (≈100–300 unknowns) BLAS/LAPACK calls on one thread, restoring the previous count after.

    Measured on the 2-core test machine: multi-threaded OpenBLAS spends most of its time synchronising on blocks of
    this size (an inverse of a 150×150 block 19 ms with 2 threads vs 5 ms with 1 under load), and its spinning
    threads slow the following small products too. A no-op when numpy's OpenBLAS is not found.
    """
    control = _blas_control()
    if not control:
        yield
        return
    get, set_ = control
    previous = int(get())
    set_(1)
    try:
        yield
    finally:
        set_(previous)


def _csr(n: int, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Symmetric adjacency of ``pairs`` (m, 2) as CSR ``(indptr, indices)``."""
    both = np.concatenate([pairs, pairs[:, ::-1]])
    both = both[both[:, 0] != both[:, 1]]
    order = np.lexsort((both[:, 1], both[:, 0]))
    both = both[order]
    indptr = np.searchsorted(both[:, 0], np.arange(n + 1))
    return indptr, both[:, 1]


def _bfs_levels(start: int, indptr: np.ndarray, indices: np.ndarray, level: np.ndarray) -> list[np.ndarray]:
    """Breadth-first levels from ``start``; ``level`` (−1 = unvisited) is filled in place with the depth."""
    levels = [np.array([start])]
    level[start] = 0
    depth = 0
    while True:
        front = levels[-1]
        starts, ends = indptr[front], indptr[front + 1]
        if len(front) == 0:
            break
        counts = ends - starts
        nb = indices[
            np.repeat(starts, counts) + (np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts))
        ]
        nb = np.unique(nb[level[nb] < 0])
        if len(nb) == 0:
            break
        depth += 1
        level[nb] = depth
        levels.append(nb)
    return levels


def is_positive_definite(S: np.ndarray) -> bool:
    """Whether the symmetric pivot ``S`` has a Cholesky factor (numpy's: the fallback without OpenBLAS)."""
    try:
        np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        return False
    return True


def negative_eigenpairs(S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The negative eigenvalues of the symmetric pivot ``S`` (ascending) and their eigenvectors as columns: its part
    of the inertia (Sylvester) and of the negative-curvature directions."""
    w, v = np.linalg.eigh(S)
    return w[w < 0], v[:, w < 0]


def inverse_pivot(S: np.ndarray, where: str) -> np.ndarray:
    """``S⁻¹`` of a pivot kept in inverse form; ``np.linalg.LinAlgError`` naming ``where`` if it is not finite."""
    Sinv = np.linalg.inv(S)
    if not np.all(np.isfinite(Sinv)):
        raise np.linalg.LinAlgError(f"non-finite inverse of {where}")
    return Sinv


def level_ordering(n: int, pairs: np.ndarray, min_block: int = 24) -> list[np.ndarray]:
    """Blocks of nodes (list of index arrays, in order) such that ``pairs`` only join equal or adjacent blocks.

    Each connected component is levelled from a pseudo-peripheral node (two BFS sweeps: start at the node of
    lowest degree, restart from the last level found), which keeps the levels narrow.
    """
    indptr, indices = _csr(n, np.asarray(pairs, dtype=np.int64).reshape(-1, 2))
    visited = np.full(n, -1, dtype=np.int64)
    blocks: list[np.ndarray] = []
    degree = np.diff(indptr)
    for seed in np.argsort(degree, kind="stable"):
        if visited[seed] >= 0:
            continue
        probe = visited.copy()
        first = _bfs_levels(int(seed), indptr, indices, probe)
        far = int(first[-1][np.argmin(degree[first[-1]])])
        levels = _bfs_levels(far, indptr, indices, visited)
        current: list[np.ndarray] = []
        size = 0
        for lev in levels:
            current.append(lev)
            size += len(lev)
            if size >= min_block:
                blocks.append(np.concatenate(current))
                current, size = [], 0
        if current:
            if blocks and size < min_block // 2 and _same_component(blocks[-1], levels):
                blocks[-1] = np.concatenate([blocks[-1], *current])
            else:
                blocks.append(np.concatenate(current))
    return blocks


def _same_component(block: np.ndarray, levels: list[np.ndarray]) -> bool:
    return bool(np.isin(block[:1], np.concatenate(levels)).all())


class BlockTridiagonal:
    """Storage and solver for a symmetric 3×3-node-block matrix with the block-tridiagonal structure above."""

    def __init__(self, n_nodes: int, pairs: np.ndarray, min_block: int = 24):
        self.n_nodes = n_nodes
        self.blocks = level_ordering(n_nodes, pairs, min_block)
        self.block_of = np.empty(n_nodes, dtype=np.int64)
        self.local = np.empty(n_nodes, dtype=np.int64)
        self.sizes = np.array([3 * len(b) for b in self.blocks], dtype=np.int64)
        for k, b in enumerate(self.blocks):
            self.block_of[b] = k
            self.local[b] = np.arange(len(b))
        self.dofs = [(3 * b[:, None] + np.arange(3)).reshape(-1) for b in self.blocks]
        diag = self.sizes**2
        sub = self.sizes[:-1] * self.sizes[1:]
        self.diag_offset = np.concatenate([[0], np.cumsum(diag)])[:-1]
        self.sub_offset = diag.sum() + np.concatenate([[0], np.cumsum(sub)])[: len(sub)]
        self.storage_size = int(diag.sum() + sub.sum())

    def scatter_index(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Flat storage index ``(m, 3, 3)`` of the 3×3 block (node ``rows[m]``, node ``cols[m]``).

        Blocks above the diagonal (they are transposes of stored ones) map to ``storage_size`` (a dump slot).
        """
        br, bc = self.block_of[rows], self.block_of[cols]
        if np.any(np.abs(br - bc) > 1):
            raise ValueError("coupling outside the block-tridiagonal structure (ordering built from other pairs)")
        R = 3 * self.local[rows][:, None, None] + np.arange(3)[None, :, None]
        C = 3 * self.local[cols][:, None, None] + np.arange(3)[None, None, :]
        out = np.full((len(rows), 3, 3), self.storage_size, dtype=np.int64)
        same = br == bc
        s = self.sizes[br][:, None, None]
        out[same] = (self.diag_offset[br][:, None, None] + R * s + C)[same]
        below = br == bc + 1
        sc = self.sizes[bc][:, None, None]
        if np.any(below):
            out[below] = self.sub_offset[bc[below]][:, None, None] + R[below] * sc[below] + C[below]
        return out

    def assemble(self, index: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Sum ``values`` into flat storage at ``index`` (same shapes); returns the storage vector."""
        return np.bincount(index.reshape(-1), weights=values.reshape(-1), minlength=self.storage_size + 1)

    def diagonal(self, storage: np.ndarray) -> np.ndarray:
        """The matrix diagonal in natural dof order (``3n``)."""
        out = np.empty(3 * self.n_nodes)
        for k, s in enumerate(self.sizes):
            d = storage[self.diag_offset[k] : self.diag_offset[k] + s * s].reshape(s, s)
            out[self.dofs[k]] = np.diag(d)
        return out

    def dense(self, storage: np.ndarray) -> np.ndarray:
        """The symmetric matrix held in ``storage`` as a dense array, natural dof order (tests and checks)."""
        n = 3 * self.n_nodes
        out = np.zeros((n, n))
        for k, s in enumerate(self.sizes):
            d = storage[self.diag_offset[k] : self.diag_offset[k] + s * s].reshape(s, s)
            out[np.ix_(self.dofs[k], self.dofs[k])] += 0.5 * (d + d.T)
            if k + 1 < len(self.sizes):
                b = storage[self.sub_offset[k] : self.sub_offset[k] + self.sizes[k + 1] * s].reshape(
                    self.sizes[k + 1], s
                )
                out[np.ix_(self.dofs[k + 1], self.dofs[k])] += b
                out[np.ix_(self.dofs[k], self.dofs[k + 1])] += b.T
        return out

    def factor(
        self,
        storage: np.ndarray,
        shift: np.ndarray | float = 0.0,
        inertia: bool = False,
        definite_only: bool = False,
    ) -> BlockFactor:
        """Block-Thomas factorisation of ``A + diag(shift)``, kept for cheap repeated solves.

        Every pivot (Schur complement) ``S_k = D_k + shift − B_{k−1} S_{k−1}⁻¹ B_{k−1}ᵀ`` is stored in one of two
        forms, chosen per block:

        * *Cholesky* (with numpy's OpenBLAS, :mod:`.lapack`): ``S_k = U_kᵀ U_k`` (``potrf``) and the coupling
          ``W_k = U_k⁻ᵀ B_kᵀ`` (``trsm``); the next pivot subtracts ``W_kᵀ W_k`` (``syrk``). About 2.3 s³ flops per
          block of s unknowns.
        * *inverse* (a pivot that is not positive definite, or every pivot when the OpenBLAS routines are not
          found or :data:`.lapack.ENABLED` is false): ``S_k⁻¹`` and ``X_k = S_k⁻¹ B_kᵀ``; the next pivot subtracts
          ``B_k X_k``. About 6.7 s³ flops per block.

        One solve (:meth:`BlockFactor.apply`) is then two triangular solves or one product with ``S_k⁻¹`` and two
        products with the coupling per block (about ``3 Σ s_k²`` flops either way): small beside the factorisation.
        Raises ``np.linalg.LinAlgError`` for a singular or non-finite block; the caller increases the shift.

        With ``inertia`` the factorisation also counts the negative eigenvalues of the matrix: block elimination
        without pivoting is the congruence ``A = L diag(S_k) Lᵀ``, so by Sylvester's law the matrix has as many
        negative eigenvalues as the pivots ``S_k`` together. Each ``S_k`` is tried by Cholesky; only where that
        fails are its eigenvalues computed (see :attr:`BlockFactor.negative_pivots`,
        :meth:`BlockFactor.negative_direction`).

        With ``definite_only`` (and ``inertia``) the elimination stops at the first pivot that is not positive
        definite: the caller only wants a factorisation of a positive definite matrix (a Newton step) and will not
        use an indefinite one. The factor returned then has ``negative_pivots == 1`` (at least one; the count is not
        finished) and ``complete`` false, and cannot solve. Away from a saddle this saves the eigenvalues and
        inverses of every later pivot: an exact Hessian found indefinite costs ~30 instead of ~110 ms at 3,000 faces.
        """
        shift_vec = np.broadcast_to(np.asarray(shift, dtype=np.float64), (3 * self.n_nodes,))
        lib = lapack.routines()
        K = len(self.blocks)
        chols: list[np.ndarray | None] = []
        inverses: list[np.ndarray | None] = []
        couplings: list[np.ndarray | None] = []
        negative = 0
        lowest: tuple[float, int, np.ndarray | None] = (0.0, -1, None)

        def sub(k: int) -> np.ndarray:
            """``B_k``: the block (k + 1, k) below the diagonal."""
            return storage[self.sub_offset[k] : self.sub_offset[k] + self.sizes[k + 1] * self.sizes[k]].reshape(
                self.sizes[k + 1], self.sizes[k]
            )

        def pivot(k: int, full: bool) -> np.ndarray:
            """``S_k``; after a Cholesky pivot only its upper triangle is updated unless ``full``."""
            s = self.sizes[k]
            D = storage[self.diag_offset[k] : self.diag_offset[k] + s * s].reshape(s, s)
            S = D + D.T  # filled from both triangles; keep it exactly symmetric
            S *= 0.5
            S.flat[:: s + 1] += shift_vec[self.dofs[k]]
            if k > 0:
                if chols[k - 1] is not None:
                    lib.subtract_gram(S, couplings[k - 1])
                    if full:
                        S = np.triu(S) + np.triu(S, 1).T
                else:
                    S -= sub(k - 1) @ couplings[k - 1]
            return S

        def stopped() -> BlockFactor:
            """The factorisation stopped at its first indefinite pivot (``definite_only``): it cannot solve."""
            out = BlockFactor(self.dofs, chols, inverses, couplings, 3 * self.n_nodes, lib)
            out.negative_pivots, out.complete = 1, False
            return out

        for k in range(K):
            if lib is not None:
                U = pivot(k, full=False)
                if lib.cholesky(U):
                    # a NaN anywhere in S_k reaches the diagonal of U_k; +inf there (an infinitely stiff degree
                    # of freedom) is kept, as the inverse keeps it (its row and column of S_k⁻¹ are zero)
                    if np.isnan(np.diagonal(U)).any():
                        raise np.linalg.LinAlgError(f"non-finite Cholesky factor of block {k}")
                    chols.append(U)
                    inverses.append(None)
                    W = None
                    if k < K - 1:
                        W = np.array(sub(k).T, order="C")  # a copy: solved in place
                        lib.solve_upper_transposed(U, W)
                    couplings.append(W)
                    continue
                if inertia and definite_only:
                    return stopped()
                S = pivot(k, full=True)  # not positive definite: its eigenvalues and inverse
                positive_definite = False
            else:
                S = pivot(k, full=True)
                positive_definite = not inertia or is_positive_definite(S)
            if inertia and not positive_definite:
                if definite_only:
                    return stopped()
                values, vectors = negative_eigenpairs(S)
                negative += len(values)
                if len(values) and values[0] < lowest[0]:
                    lowest = (float(values[0]), k, vectors[:, 0])
            Sinv = inverse_pivot(S, f"block {k}")
            chols.append(None)
            inverses.append(Sinv)
            couplings.append(Sinv @ sub(k).T if k < K - 1 else None)
        out = BlockFactor(self.dofs, chols, inverses, couplings, 3 * self.n_nodes, lib)
        out.negative_pivots = negative if inertia else None
        out.lowest_pivot = lowest
        return out

    def solve(self, storage: np.ndarray, rhs: np.ndarray, shift: np.ndarray | float = 0.0) -> np.ndarray:
        """Solve ``(A + diag(shift)) x = rhs`` (natural dof order, length ``3n``) by block Thomas elimination."""
        return self.factor(storage, shift).apply(rhs)


class BlockFactor:
    """A block-Thomas factorisation (see :meth:`BlockTridiagonal.factor`); :meth:`apply` solves with it.

    Per block ``k`` either ``chols[k]`` (the Cholesky factor ``U_k``, ``S_k = U_kᵀ U_k``, in its upper triangle;
    the strict lower triangle is not used) or ``inverses[k]`` (``S_k⁻¹``) is set; ``couplings[k]``
    (``s_k × s_{k+1}``, ``None`` for the last block) is ``W_k = U_k⁻ᵀ B_kᵀ`` or ``X_k = S_k⁻¹ B_kᵀ`` accordingly.
    ``lib`` is the :class:`.lapack.OpenBLAS` that solves with ``U_k``.
    """

    def __init__(self, dofs, chols, inverses, couplings, size: int, lib: lapack.OpenBLAS | None = None):
        self.dofs, self.chols, self.inverses, self.couplings, self.size = dofs, chols, inverses, couplings, size
        self.order = np.concatenate(dofs)
        """The degrees of freedom in block order: one gather and one scatter per solve instead of two per block."""
        self.bounds = np.concatenate([[0], np.cumsum([len(d) for d in dofs])])
        self.lib = lib
        self.negative_pivots: int | None = None
        """Number of negative eigenvalues of the factored matrix (``None`` when not computed)."""
        self.lowest_pivot: tuple[float, int, np.ndarray | None] = (0.0, -1, None)
        """``(eigenvalue, block, eigenvector)`` of the most negative pivot eigenvalue found (block −1: none)."""
        self.complete = True
        """False for a factorisation stopped at its first indefinite pivot (``definite_only``): it cannot solve."""

    def negative_direction(self) -> np.ndarray | None:
        """A direction ``w`` with ``wᵀ A w = λ_min(S_k) < 0`` (natural dof order), or ``None`` if A is not indefinite.

        ``w = L⁻ᵀ z`` with ``z`` the lowest eigenvector of the pivot ``S_k`` (zero elsewhere), so
        ``wᵀ A w = zᵀ S_k z``: a back substitution from block ``k`` down to block 0 through
        ``X_m = S_m⁻¹ B_mᵀ`` (``= U_m⁻¹ W_m`` for a Cholesky pivot).
        """
        value, k, z = self.lowest_pivot
        if k < 0 or z is None or value >= 0:
            return None
        out = np.zeros(self.size)
        nxt = np.array(z, dtype=np.float64)
        out[self.dofs[k]] = nxt
        for m in range(k - 1, -1, -1):
            nxt = -(self.couplings[m] @ nxt)
            if self.chols[m] is not None:
                self.lib.solve_upper_vector(self.chols[m], nxt)
            out[self.dofs[m]] = nxt
        return out

    def apply(self, rhs: np.ndarray) -> np.ndarray:
        """``(A + diag(shift))⁻¹ rhs`` for a flat ``3n`` vector.

        Forward: ``g_k = r_k − B_{k−1} S_{k−1}⁻¹ g_{k−1}``, which is ``r_k − W_{k−1}ᵀ U_{k−1}⁻ᵀ g_{k−1}`` or
        ``r_k − X_{k−1}ᵀ g_{k−1}``; back: ``x_k = S_k⁻¹ g_k − X_k x_{k+1}``, which is
        ``U_k⁻¹ (U_k⁻ᵀ g_k − W_k x_{k+1})`` for a Cholesky pivot.
        """
        rhs = np.asarray(rhs, dtype=np.float64)
        K = len(self.couplings)
        bounds = self.bounds
        r = rhs[self.order]  # block order, a copy: every block below is a contiguous view of it
        half: list[np.ndarray] = []  # U_k⁻ᵀ g_k (Cholesky pivot) or S_k⁻¹ g_k (inverse)
        carry = None  # what the coupling of the previous block multiplies: U⁻ᵀ g or g
        for k in range(K):
            g = r[bounds[k] : bounds[k + 1]]
            if k > 0:
                g -= self.couplings[k - 1].T @ carry
            if self.chols[k] is not None:
                self.lib.solve_upper_vector(self.chols[k], g, transpose=True)
                half.append(g)
            else:
                half.append(self.inverses[k] @ g)
            carry = g
        y = np.empty(self.size)
        nxt = None
        for k in range(K - 1, -1, -1):
            t = half[k] if nxt is None else half[k] - self.couplings[k] @ nxt
            if self.chols[k] is not None:
                self.lib.solve_upper_vector(self.chols[k], t)
            nxt = t
            y[bounds[k] : bounds[k + 1]] = nxt
        out = np.empty(self.size)
        out[self.order] = y
        return out
