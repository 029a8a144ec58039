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
import ctypes
import glob
import os
from collections.abc import Iterator

import numpy as np

_BLAS_CONTROL: tuple | None = None


def _blas_control() -> tuple:
    """``(get, set)`` thread-count functions of the OpenBLAS that numpy loaded, or ``()`` if none is found.

    numpy's wheels bundle OpenBLAS in ``numpy.libs`` (symbols with a ``64_`` suffix); this is what ``threadpoolctl``
    does, without the dependency.
    """
    global _BLAS_CONTROL
    if _BLAS_CONTROL is None:
        _BLAS_CONTROL = ()
        base = os.path.dirname(os.path.dirname(np.__file__))
        for path in glob.glob(os.path.join(base, "numpy.libs", "libopenblas*")) + glob.glob(
            os.path.join(os.path.dirname(np.__file__), ".libs", "libopenblas*")
        ):
            try:
                lib = ctypes.CDLL(path)
            except OSError:
                continue
            for suffix in ("64_", ""):
                get = getattr(lib, "openblas_get_num_threads" + suffix, None)
                set_ = getattr(lib, "openblas_set_num_threads" + suffix, None)
                if get is not None and set_ is not None:
                    _BLAS_CONTROL = (get, set_)
                    return _BLAS_CONTROL
    return _BLAS_CONTROL


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

    def factor(self, storage: np.ndarray, shift: np.ndarray | float = 0.0, inertia: bool = False) -> BlockFactor:
        """Block-Thomas factorisation of ``A + diag(shift)``, kept for cheap repeated solves.

        For every block the inverse of its Schur complement ``S_k`` and ``X_k = S_k⁻¹ B_kᵀ`` are stored, so one
        solve is only matrix–vector products (about ``3 Σ s_k²`` flops), cheap enough to serve as the
        preconditioner of conjugate gradients over several Newton iterations and animation frames.
        Raises ``np.linalg.LinAlgError`` for a singular or non-finite block; the caller increases the shift.

        With ``inertia`` the factorisation also counts the negative eigenvalues of the matrix: block elimination
        without pivoting is the congruence ``A = L diag(S_k) Lᵀ``, so by Sylvester's law the matrix has as many
        negative eigenvalues as the pivots ``S_k`` together. Each ``S_k`` is tried by Cholesky; only where that
        fails are its eigenvalues computed (see :attr:`BlockFactor.negative_pivots`,
        :meth:`BlockFactor.negative_direction`).
        """
        shift_vec = np.broadcast_to(np.asarray(shift, dtype=np.float64), (3 * self.n_nodes,))
        K = len(self.blocks)
        inverses: list[np.ndarray] = []
        xs: list[np.ndarray | None] = []
        subs: list[np.ndarray | None] = []
        prev_X = prev_B = None
        negative = 0
        lowest: tuple[float, int, np.ndarray | None] = (0.0, -1, None)
        for k in range(K):
            s = self.sizes[k]
            D = storage[self.diag_offset[k] : self.diag_offset[k] + s * s].reshape(s, s)
            S = 0.5 * (D + D.T)  # filled from both triangles; keep it exactly symmetric
            S[np.diag_indices(s)] += shift_vec[self.dofs[k]]
            if k > 0:
                S -= prev_B @ prev_X
            if inertia:
                try:
                    np.linalg.cholesky(S)
                except np.linalg.LinAlgError:
                    w, v = np.linalg.eigh(S)
                    negative += int(np.sum(w < 0))
                    if w[0] < lowest[0]:
                        lowest = (float(w[0]), k, v[:, 0])
            Sinv = np.linalg.inv(S)
            if not np.all(np.isfinite(Sinv)):
                raise np.linalg.LinAlgError(f"non-finite inverse of block {k}")
            inverses.append(Sinv)
            if k < K - 1:
                B = storage[self.sub_offset[k] : self.sub_offset[k] + self.sizes[k + 1] * s].reshape(
                    self.sizes[k + 1], s
                )
                prev_X, prev_B = Sinv @ B.T, B
            else:
                prev_X = prev_B = None
            xs.append(prev_X)
            subs.append(prev_B)
        out = BlockFactor(self.dofs, inverses, xs, subs, 3 * self.n_nodes)
        out.negative_pivots = negative if inertia else None
        out.lowest_pivot = lowest
        return out

    def solve(self, storage: np.ndarray, rhs: np.ndarray, shift: np.ndarray | float = 0.0) -> np.ndarray:
        """Solve ``(A + diag(shift)) x = rhs`` (natural dof order, length ``3n``) by block Thomas elimination."""
        return self.factor(storage, shift).apply(rhs)


class BlockFactor:
    """A block-Thomas factorisation (see :meth:`BlockTridiagonal.factor`); :meth:`apply` solves with it."""

    def __init__(self, dofs, inverses, xs, subs, size: int):
        self.dofs, self.inverses, self.xs, self.subs, self.size = dofs, inverses, xs, subs, size
        self.negative_pivots: int | None = None
        """Number of negative eigenvalues of the factored matrix (``None`` when not computed)."""
        self.lowest_pivot: tuple[float, int, np.ndarray | None] = (0.0, -1, None)
        """``(eigenvalue, block, eigenvector)`` of the most negative pivot eigenvalue found (block −1: none)."""

    def negative_direction(self) -> np.ndarray | None:
        """A direction ``w`` with ``wᵀ A w = λ_min(S_k) < 0`` (natural dof order), or ``None`` if A is not indefinite.

        ``w = L⁻ᵀ z`` with ``z`` the lowest eigenvector of the pivot ``S_k`` (zero elsewhere), so
        ``wᵀ A w = zᵀ S_k z``: a back substitution through the stored ``X_k`` from block ``k`` down to block 0.
        """
        value, k, z = self.lowest_pivot
        if k < 0 or z is None or value >= 0:
            return None
        out = np.zeros(self.size)
        nxt = z
        out[self.dofs[k]] = nxt
        for m in range(k - 1, -1, -1):
            nxt = -self.xs[m] @ nxt
            out[self.dofs[m]] = nxt
        return out

    def apply(self, rhs: np.ndarray) -> np.ndarray:
        """``(A + diag(shift))⁻¹ rhs`` for a flat ``3n`` vector."""
        K = len(self.inverses)
        Z: list[np.ndarray] = []
        prev_z = None
        for k in range(K):
            g = rhs[self.dofs[k]]
            if k > 0:
                g = g - self.subs[k - 1] @ prev_z
            prev_z = self.inverses[k] @ g
            Z.append(prev_z)
        out = np.empty(self.size)
        nxt = Z[-1]
        out[self.dofs[-1]] = nxt
        for k in range(K - 2, -1, -1):
            nxt = Z[k] - self.xs[k] @ nxt
            out[self.dofs[k]] = nxt
        return out
