"""Sparse symmetric solves with numpy only: nested-dissection ordering + multifrontal block Cholesky.

The Newton solver factors the 3n×3n Hessian of the bar-and-hinge model, whose couplings (bars, triangles, a hinge's
two wing nodes) form the graph of a *planar sheet*. :class:`.linalg.BlockTridiagonal` orders that graph by
breadth-first levels, which makes the matrix a band of width ≈ √n nodes: its factorisation costs ≈ n² flops.
Nested dissection (George 1973; George & Liu's automatic variant) costs ≈ n^1.5 on a 2D graph: a middle BFS level
is a vertex separator that splits the sheet in two; the two halves are ordered first (recursively) and the
separator last, so the halves never couple and their elimination creates no fill between them.

:class:`NestedDissection` computes that ordering from the graph once per mesh (each separator and each leaf part
is a *supernode*, a set of nodes eliminated together as one dense pivot), the elimination tree of the supernodes,
the sparsity structure of the factor and every index map the numeric work needs. :meth:`NestedDissection.factor`
is then a multifrontal block Cholesky over the tree: one dense pivot, one triangular solve and one rank update
per supernode (LAPACK/BLAS through :mod:`.lapack`), the update passed to the parent supernode by an extend-add with
a precomputed index. Small supernodes are merged into their parents where a cost model of the measured kernel
rates and overheads says one bigger dense pivot is cheaper (:func:`_amalgamate`), and the rows of a pivot that do
not couple to its boundary are ordered first and skipped by the triangular solve and the rank update. It has the
interface of :class:`.linalg.BlockTridiagonal` (``scatter_index``, ``assemble``, ``diagonal``, ``factor``; the
factor's ``apply``, inertia and negative-curvature direction), so :class:`.newton.HessianAssembler` uses either.
"""

from __future__ import annotations

from collections.abc import Generator

import numpy as np

from .. import run_to_end
from . import lapack
from .linalg import _csr, inverse_pivot, is_positive_definite, negative_eigenpairs

LEAF_NODES = 16
"""Default largest part (in nodes) that is not dissected further. Small, because :func:`_amalgamate` then merges
what is cheaper as one pivot: the factorisation times of leaves of 8 to 32 nodes are within noise of each other on
the CircularPleat-antiFacet and Carved_Cylinder fixtures (measured one thread)."""


DENSE_FACTOR = 3.0
"""A node coupled to more than this many times the median node's neighbours (and to more than :data:`DENSE_MIN`) is
*dense*: ordered last, in a root supernode of its own, and left out of the levelling. A constrained Delaunay
triangulation without interior points fans a region bounded by few nodes from them (the four corners of a square
border around a circle: 90–140 triangles each), and through such a hub every node is two steps from every other:
the BFS levels swell to a fifth of the sheet and so do the separators (concentric circles in a square, 5,902 faces:
13.3 GFlop per factorisation, 0.42 s; 0.36 GFlop without the hubs). Measured on the fixtures, the examples and
twelve drawn patterns: 3× took the flops of all 27 meshes from 14.8 to 1.7 GFlop, 8× or 6× to 1.9, 4× to 1.8; no
mesh without such a fan changes (their largest node has at most twice the median)."""

DENSE_MIN = 48
"""Fewest couplings of a dense node (see :data:`DENSE_FACTOR`): a crease vertex where a few creases meet is not."""


def dense_nodes(indptr: np.ndarray) -> np.ndarray:
    """The dense nodes of a graph (:data:`DENSE_FACTOR`), as node indices."""
    degree = np.diff(indptr)
    if not len(degree):
        return np.zeros(0, dtype=np.int64)
    limit = max(DENSE_FACTOR * float(np.median(degree)), DENSE_MIN)
    return np.flatnonzero(degree > limit).astype(np.int64)


def _neighbours(front: np.ndarray, indptr: np.ndarray, indices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All neighbours of the nodes ``front`` (CSR rows, concatenated) and, for each, its position in ``front``."""
    starts = indptr[front]
    counts = indptr[front + 1] - starts
    owner = np.repeat(np.arange(len(front)), counts)
    flat = np.arange(int(counts.sum())) + np.repeat(starts - (np.cumsum(counts) - counts), counts)
    return indices[flat], owner


def _bfs(start: int, indptr: np.ndarray, indices: np.ndarray, allowed: np.ndarray, dist: np.ndarray) -> list:
    """Breadth-first levels from ``start`` inside the nodes where ``allowed`` is true.

    ``dist`` (−1 = unvisited) is filled with each visited node's level; the caller resets it.
    """
    levels = [np.array([start], dtype=np.int64)]
    dist[start] = 0
    while True:
        nb, _ = _neighbours(levels[-1], indptr, indices)
        nb = nb[allowed[nb] & (dist[nb] < 0)]
        if len(nb) == 0:
            return levels
        nb = np.unique(nb)
        dist[nb] = len(levels)
        levels.append(nb)


def _separator(
    levels: list, indptr: np.ndarray, indices: np.ndarray, dist: np.ndarray
) -> tuple[np.ndarray, list[np.ndarray]]:
    """A vertex separator of one connected part from its BFS ``levels`` (``dist`` holds the levels): ``(separator,
    [lower side, upper side])``.

    Couplings join equal or adjacent levels only, so any level ``m`` separates the levels below it from those
    above. Of the levels that leave each side at least a quarter of the nodes the smallest is taken (the middle
    one when none does). Then separator nodes with no neighbour on one side are moved to the other side (the side
    that takes more of them): the separator stays one, and smaller.
    """
    sizes = np.array([len(level) for level in levels])
    total = int(sizes.sum())
    cum = np.cumsum(sizes)
    h = len(levels) - 1
    m_all = np.arange(1, h)
    below, above = cum[m_all - 1], total - cum[m_all]
    fair = np.minimum(below, above) >= 0.25 * total
    middle = int(np.clip(np.searchsorted(cum, total / 2), 1, h - 1))
    if np.any(fair):
        candidates = m_all[fair]
        # the smallest level, the nearest to the middle among equals
        m = int(candidates[np.lexsort((np.abs(candidates - middle), sizes[candidates]))[0]])
    else:
        m = middle
    sep = levels[m]
    nb, owner = _neighbours(sep, indptr, indices)
    d = dist[nb]
    has_up = np.bincount(owner[d == m + 1], minlength=len(sep)) > 0
    has_down = np.bincount(owner[d == m - 1], minlength=len(sep)) > 0
    lower = list(levels[:m])
    upper = list(levels[m + 1 :])
    if np.count_nonzero(~has_up) >= np.count_nonzero(~has_down):
        lower.append(sep[~has_up])
        sep = sep[has_up]
    else:
        upper.append(sep[~has_down])
        sep = sep[has_down]
    return sep, [np.concatenate(lower), np.concatenate(upper)]


def _along(
    sep: np.ndarray, indptr: np.ndarray, indices: np.ndarray, dist: np.ndarray, degree: np.ndarray
) -> np.ndarray:
    """The separator ``sep`` reordered along itself: breadth-first inside it from a pseudo-peripheral node, one
    connected piece after the other.

    A separator is a curve across the sheet; a child supernode's boundary is an arc of each ancestor separator it
    touches, so ordered along the curve it is one contiguous range of the parent's front, and the extend-add of
    its update is a few dense slices (:meth:`NestedDissection._extend_plan`) instead of a scatter per entry.
    ``dist`` is used as scratch and left at −1.
    """
    if len(sep) <= 2:
        return sep
    inside = np.zeros(len(dist), dtype=bool)
    inside[sep] = True
    out: list[np.ndarray] = []
    left = sep
    while len(left):
        seed = int(left[np.argmin(degree[left])])
        levels = _bfs(seed, indptr, indices, inside, dist)
        piece = np.concatenate(levels)
        dist[piece] = -1
        if len(levels) > 1:
            far = int(levels[-1][np.argmin(degree[levels[-1]])])
            levels = _bfs(far, indptr, indices, inside, dist)
            dist[piece] = -1
        out.extend(levels)
        inside[piece] = False
        left = left[inside[left]]
    return np.concatenate(out)


def dissect_pairs(n: int, pairs: np.ndarray, min_block: int | None = None) -> tuple[list[np.ndarray], np.ndarray]:
    """:func:`dissect` of the graph of ``pairs`` with leaves of at most ``min_block`` nodes (:data:`LEAF_NODES` by
    default): the most expensive part of :class:`NestedDissection`'s setup (~95 ms of ~160 at 3,000 faces, 220 ms
    at 4,000 faces on a clef of many strips), which a Blender job runs in units (:func:`dissect_pairs_steps`) and
    passes on (``dissection=``)."""
    return run_to_end(dissect_pairs_steps(n, pairs, min_block))


def dissect_pairs_steps(
    n: int, pairs: np.ndarray, min_block: int | None = None
) -> Generator[None, None, tuple[list[np.ndarray], np.ndarray]]:
    """:func:`dissect_pairs` one unit per ``next`` (:func:`dissect_steps`); the generator returns its value."""
    indptr, indices = _csr(n, np.asarray(pairs, dtype=np.int64).reshape(-1, 2))
    return (yield from dissect_steps(n, indptr, indices, _leaf_size(min_block)))


def _leaf_size(min_block: int | None) -> int:
    """The largest part not dissected further: ``min_block`` nodes, :data:`LEAF_NODES` by default."""
    return LEAF_NODES if min_block is None else max(1, int(min_block))


def dissect(n: int, indptr: np.ndarray, indices: np.ndarray, leaf: int) -> tuple[list[np.ndarray], np.ndarray]:
    """Nested dissection of the graph ``(indptr, indices)`` on ``n`` nodes: ``(supernodes, parent)``, at once
    (:func:`dissect_steps` run to its end)."""
    return run_to_end(dissect_steps(n, indptr, indices, leaf))


def dissect_steps(
    n: int, indptr: np.ndarray, indices: np.ndarray, leaf: int
) -> Generator[None, None, tuple[list[np.ndarray], np.ndarray]]:
    """Nested dissection of the graph ``(indptr, indices)`` on ``n`` nodes: ``(supernodes, parent)``.

    The supernodes (node index arrays) are in creation order, every parent before its children; ``parent[s]`` is
    the supernode that separated the part ``s`` came from (−1 at the top). A part is split into its connected
    components; a component of at most ``leaf`` nodes is a leaf (small sibling components are grouped into one
    leaf: they do not couple, and one dense pivot costs less than many tiny ones); a larger one is levelled from a
    pseudo-peripheral node (BFS sweeps from a lowest-degree node of the last level while the depth grows) and cut
    at a level (:func:`_separator`), from whichever end of the pseudo-diameter gives the smaller separator (12–26 %
    fewer flops on grids and on Carved_Cylinder than one end only); its two sides are parts again. A component
    whose levelling has fewer than three levels (a clique-like graph) is a leaf whatever its size. Dense nodes
    (:func:`dense_nodes`, hubs of a fan) are the root supernode, ordered last, and the rest is dissected without them.
    Yields (``None``) after each component is levelled and cut or set aside, so a Blender job can stop between
    any two; the generator returns ``(supernodes, parent)``.
    """
    degree = np.diff(indptr)
    allowed = np.zeros(n, dtype=bool)
    dist = np.full(n, -1, dtype=np.int64)
    supernodes: list[np.ndarray] = []
    parent: list[int] = []
    hubs = dense_nodes(indptr)
    if len(hubs) == n:  # nothing would be left to dissect
        hubs = hubs[:0]
    if len(hubs):
        supernodes.append(hubs)
        parent.append(-1)
    rest = np.setdiff1d(np.arange(n, dtype=np.int64), hubs)
    stack: list[tuple[np.ndarray, int]] = [(rest, len(supernodes) - 1)] if n else []
    while stack:
        nodes, par = stack.pop()
        allowed[nodes] = True
        left = nodes
        group: list[np.ndarray] = []  # small components waiting to be one leaf
        group_size = 0
        while len(left):
            seed = int(left[np.argmin(degree[left])])
            levels = _bfs(seed, indptr, indices, allowed, dist)
            comp = np.concatenate(levels)
            dist[comp] = -1
            if len(comp) > leaf and len(levels) >= 3:
                other = None  # the levelling from the other end of the pseudo-diameter
                for _sweep in range(3):
                    last = levels[-1]
                    far = int(last[np.argmin(degree[last])])
                    again = _bfs(far, indptr, indices, allowed, dist)
                    dist[comp] = -1
                    if len(again) <= len(levels):
                        other = again
                        break
                    other, levels = levels, again
                best = None
                for cand in [levels] + ([other] if other is not None and len(other) >= 3 else []):
                    for k, level in enumerate(cand):
                        dist[level] = k
                    found = _separator(cand, indptr, indices, dist)
                    dist[comp] = -1
                    if best is None or len(found[0]) < len(best[0]):
                        best = found
                sep, sides = best
                sep = _along(sep, indptr, indices, dist, degree)
                sid = len(supernodes)
                supernodes.append(sep)
                parent.append(par)
                stack.extend((side, sid) for side in sides if len(side))
            elif len(comp) > leaf:
                supernodes.append(comp)
                parent.append(par)
            else:
                if group_size + len(comp) > leaf and group:
                    supernodes.append(np.concatenate(group))
                    parent.append(par)
                    group, group_size = [], 0
                group.append(comp)
                group_size += len(comp)
            allowed[comp] = False
            left = left[allowed[left]]
            yield
        if group:
            supernodes.append(np.concatenate(group))
            parent.append(par)
    return supernodes, np.array(parent, dtype=np.int64)


def _postorder(parent: np.ndarray, weight: np.ndarray | None = None) -> np.ndarray:
    """A postorder of the forest ``parent`` (children before their parent, every subtree contiguous).

    With ``weight`` (per node of the forest), the children of each node come heaviest subtree first: the parent's
    front is made when its first child is done, and the lighter subtrees after it evict less of it from the cache
    before they add their updates (multifrontal practice, Liu 1986).
    """
    K = len(parent)
    children: list[list[int]] = [[] for _ in range(K)]
    roots = []
    for s in range(K):
        (children[parent[s]] if parent[s] >= 0 else roots).append(s)
    if weight is not None:
        total = np.asarray(weight, dtype=np.float64).copy()
        for s in _postorder(parent):
            if parent[s] >= 0:
                total[parent[s]] += total[s]
        for kids in children:
            kids.sort(key=lambda c: -total[c])
    out: list[int] = []
    stack = [(r, False) for r in reversed(roots)]
    while stack:
        s, done = stack.pop()
        if done:
            out.append(s)
            continue
        stack.append((s, True))
        stack.extend((c, False) for c in reversed(children[s]))
    return np.array(out, dtype=np.int64)


def _symbolic(n: int, sets: list[np.ndarray], tree: np.ndarray, indptr: np.ndarray, indices: np.ndarray) -> tuple:
    """The supernodes ``sets`` with parents ``tree`` (any order, parents need not come first) put in postorder:
    ``(supernodes, parent, children, start, stop, position, boundary)`` (see :class:`NestedDissection`).

    The boundary of ``s`` is ``(neighbours of s ∪ boundaries of its children)`` less ``s`` and everything
    eliminated before it: in a nested-dissection tree, nodes of ancestors of ``s`` only.
    """
    post = _postorder(tree, np.array([len(s) for s in sets], dtype=np.float64) ** 1.5)
    rank = np.empty(len(post), dtype=np.int64)
    rank[post] = np.arange(len(post))
    supernodes = [sets[s] for s in post]
    K = len(supernodes)
    parent = np.array([rank[tree[s]] if tree[s] >= 0 else -1 for s in post], dtype=np.int64)
    children: list[list[int]] = [[] for _ in range(K)]
    for s in range(K):
        if parent[s] >= 0:
            children[parent[s]].append(s)
    counts = np.array([len(s) for s in supernodes], dtype=np.int64)
    stop = np.cumsum(counts)
    start = stop - counts
    position = np.empty(n, dtype=np.int64)
    if K:
        position[np.concatenate(supernodes)] = np.arange(n)
    boundary: list[np.ndarray] = []
    for s in range(K):
        nb, _ = _neighbours(supernodes[s], indptr, indices)
        cand = np.concatenate([position[nb], *(boundary[c] for c in children[s])])
        boundary.append(np.unique(cand[cand >= stop[s]]))
    return supernodes, parent, children, start, stop, position, boundary


SPEED = (13e9, 15e9, 30e9, 40e-6, 3e-9, 1.5e-9)
"""Cost model of one supernode for :func:`_amalgamate`: flop rates of ``potrf``, ``trsm`` and ``syrk``, the fixed
time per supernode (Python and call overheads of a factorisation and of ~1.5 solves), the time per entry of its
update moved into the parent's front and per entry of its front made (copies, zeros). Measured with one OpenBLAS
thread on the 2-core test machine (CircularPleat-antiFacet, fronts of 100–400 unknowns)."""


def _time(p: int, b: int, q: int | None = None) -> float:
    """Model time of a supernode of ``p`` pivot and ``b`` boundary unknowns, ``q`` of the pivot's rows coupled to
    the boundary (all by default; :data:`SPEED`)."""
    potrf, trsm, syrk, fixed, per_update, per_front = SPEED
    q = p if q is None else q
    flops = p**3 / 3 / potrf + q * q * b / trsm + q * b * b / syrk
    return flops + fixed + per_update * b * b + per_front * (p * p + p * b + b * b)


def _coupled_rows(sym: tuple, indptr: np.ndarray, indices: np.ndarray) -> list[np.ndarray]:
    """For each supernode of the symbolic structure ``sym`` (:func:`_symbolic`), which of its nodes have a nonzero
    row in the coupling ``C = A_sB + (children's updates)``: a neighbour in ``B_s``, or membership of the
    boundary of a child whose boundary reaches beyond ``s`` (its update then couples the two)."""
    supernodes, parent, children, start, stop, position, boundary = sym
    out = []
    for s in range(len(supernodes)):
        hit = np.zeros(len(supernodes[s]), dtype=bool)
        nb, owner = _neighbours(supernodes[s], indptr, indices)
        hit[owner[position[nb] >= stop[s]]] = True
        for c in children[s]:
            bc = boundary[c]
            if len(bc) and bc[-1] >= stop[s]:
                hit[bc[bc < stop[s]] - start[s]] = True
        out.append(hit)
    return out


def _amalgamate(sym: tuple, indptr: np.ndarray, indices: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """Merge supernodes into their parents where the model (:func:`_time`) says one bigger dense pivot is cheaper.

    A child ``c`` of ``s`` merged into it leaves the boundary of ``s`` as it is (``B_c ⊆ s ∪ B_s``): the merged
    pivot has ``p_c + p_s`` unknowns and the same ``b_s``; its rows coupled to ``B_s`` are those of ``s`` and the
    nodes of ``c`` next to ``B_s`` (or in a boundary that reaches it), which :meth:`NestedDissection.factor` puts
    last, so the rows of ``c`` deep inside cost only in the Cholesky of the pivot. Merging saves a supernode's
    fixed costs and the extend-add of the child's update (``b_c²`` entries); small separators and leaves whose
    boundary is nearly their parent's whole front merge. Greedy, bottom-up (postorder): the children of a merged
    child are candidates in turn. Returns the merged ``(sets, parent)`` (members in elimination order, children
    first).
    """
    supernodes, parent, children, start, stop, position, boundary = sym
    K = len(supernodes)
    n = len(position)
    # the latest elimination position among each node's neighbours, by position
    reach = np.full(n, -1, dtype=np.int64)
    if len(indices):
        rows = np.repeat(np.arange(n), np.diff(indptr))
        np.maximum.at(reach, position[rows], position[indices])
    mark = np.zeros(n, dtype=bool)

    def coupled(members: list[int], kids: list[int], stop_s: int) -> int:
        """Unknowns of the pivot ``members`` (with children ``kids``) coupled beyond ``stop_s``."""
        pos = np.concatenate([np.arange(start[m], stop[m]) for m in members])
        hit = reach[pos] >= stop_s
        touched = [boundary[g] for g in kids if len(boundary[g]) and boundary[g][-1] >= stop_s]
        if touched:
            t = np.concatenate(touched)
            mark[t] = True
            hit |= mark[pos]
            mark[t] = False
        return 3 * int(np.count_nonzero(hit))

    size = [3 * len(s) for s in supernodes]
    bsize = [3 * len(b) for b in boundary]
    members: list[list[int]] = [[s] for s in range(K)]
    kids = [list(c) for c in children]
    rows_of = [coupled([s], kids[s], stop[s]) for s in range(K)]
    rep = np.arange(K)
    for s in range(K):
        work = list(kids[s])
        while work:
            c = work.pop()
            merged_kids = [k for k in kids[s] if k != c] + kids[c]
            q = coupled(members[c] + members[s], merged_kids, stop[s])
            apart = _time(size[c], bsize[c], rows_of[c]) + _time(size[s], bsize[s], rows_of[s])
            if _time(size[c] + size[s], bsize[s], q) < apart:
                size[s] += size[c]
                rows_of[s] = q
                members[s] = members[c] + members[s]
                rep[members[c]] = s
                kids[s] = merged_kids
                work.extend(kids[c])
    roots = [s for s in range(K) if rep[s] == s]
    index = {s: k for k, s in enumerate(roots)}
    sets = [np.concatenate([supernodes[m] for m in sorted(members[s])]) for s in roots]
    tree = np.array([index[int(rep[parent[s]])] if parent[s] >= 0 else -1 for s in roots], dtype=np.int64)
    return sets, tree


class _RestartError(Exception):
    """A pivot that was not kept turned out not to be positive definite (see :meth:`NestedDissection._factor`)."""


class NestedDissection:
    """Storage and multifrontal block-Cholesky solver for a symmetric matrix of 3×3 node blocks whose nonzero
    blocks couple the nodes of ``pairs`` (and each node with itself), in a nested-dissection order.

    Setup (once per mesh; vectorised per BFS level, a Python loop over supernodes only):

    * :func:`dissect` → supernodes, put in a postorder of their tree (``self.parent``), so that the nodes are
      eliminated in the order ``self.node_order``, each supernode a contiguous range ``start[s]:stop[s]`` of it;
    * the boundary ``B_s`` of each supernode: the later-eliminated nodes its column block of the factor reaches,
      ``(neighbours of s ∪ boundaries of its children) \\ (s and earlier)``; they all lie in ancestors of ``s``;
    * with ``amalgamate``, children merged into their parents where :func:`_amalgamate`'s cost model gains;
    * within each supernode, the nodes whose rows of the coupling are zero first (:attr:`zero_rows`);
    * storage: per supernode its pivot block ``A_ss`` (``p × p``, ``p = 3|s|``, upper triangle) followed by its
      coupling ``A_sB`` (``p × b``, ``b = 3|B_s|``), row-major: the first two parts of its front (see
      :meth:`factor`), filled by one contiguous copy;
    * per child, how its update matrix is added into the parent's front (:meth:`_extend_plan`).

    ``min_block``: the largest part (nodes) not dissected further (:data:`LEAF_NODES` by default).
    """

    def __init__(
        self,
        n_nodes: int,
        pairs: np.ndarray,
        min_block: int | None = None,
        amalgamate: bool = True,
        dissection: tuple[list[np.ndarray], np.ndarray] | None = None,
    ):
        self.n_nodes = n = int(n_nodes)
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        indptr, indices = _csr(n, pairs)
        if dissection is None:
            dissection = dissect(n, indptr, indices, _leaf_size(min_block))
        sets, tree = dissection
        sym = _symbolic(n, sets, tree, indptr, indices)
        if amalgamate:
            sets, tree = _amalgamate(sym, indptr, indices)
            sym = _symbolic(n, sets, tree, indptr, indices)
        # within each supernode the nodes whose coupling row is zero first: the triangular solve and the rank
        # update then skip them (W = U⁻ᵀ C has the zero rows of C at its top)
        coupled = _coupled_rows(sym, indptr, indices)
        sym = _symbolic(
            n, [np.concatenate([N[~c], N[c]]) for N, c in zip(sym[0], coupled, strict=True)], sym[1], indptr, indices
        )
        coupled = _coupled_rows(sym, indptr, indices)
        self.zero_rows = np.array([3 * (int(np.argmax(c)) if c.any() else len(c)) for c in coupled], dtype=np.int64)
        """Leading unknowns of each pivot whose rows of the coupling are zero (skipped by ``trsm`` and ``syrk``)."""
        self.supernodes, self.parent, self.children, self.start, self.stop, self.position, self.boundary = sym
        """``supernodes``: node indices of each supernode, in elimination (post)order; ``parent``: parent supernode
        (−1: a root); ``start``/``stop``: its range of elimination positions; ``position``: elimination position of
        each node; ``boundary``: elimination positions of the boundary nodes ``B_s`` of each, ascending."""
        K = len(self.supernodes)
        counts = self.stop - self.start
        self.node_order = np.concatenate(self.supernodes) if K else np.zeros(0, dtype=np.int64)
        """The nodes in elimination order."""
        self.supernode_of = np.repeat(np.arange(K), counts)[self.position]
        """Supernode of each node."""
        self.local = self.position - self.start[self.supernode_of]
        """Position of each node within its supernode."""
        self.first_descendant = np.arange(K)
        """First supernode of the subtree of each supernode (postorder: the subtree is ``first_descendant[s]:s+1``)."""
        for s in range(K):
            if self.parent[s] >= 0:
                p = self.parent[s]
                self.first_descendant[p] = min(self.first_descendant[p], self.first_descendant[s])
        boundary = self.boundary
        self.pivot_size = 3 * counts
        self.boundary_size = np.array([3 * len(b) for b in boundary], dtype=np.int64)
        p, b = self.pivot_size, self.boundary_size
        offset = np.concatenate([[0], np.cumsum(p * (p + b))]).astype(np.int64)
        self.offset = offset[:-1]
        """Start of each supernode's pivot block (then its coupling block) in the flat storage."""
        self.storage_size = int(offset[-1])
        self.order = (3 * self.node_order[:, None] + np.arange(3)).reshape(-1)
        """The degrees of freedom in elimination order (a solve gathers and scatters once with it)."""
        self.boundary_dofs = [(3 * bd[:, None] + np.arange(3)).reshape(-1) for bd in boundary]
        """Boundary degrees of freedom of each supernode as indices into the elimination-ordered vector."""
        # boundary lookup for scatter_index: key s·n + position, ascending
        self._bkeys = np.concatenate([s * n + bd for s, bd in enumerate(boundary)]) if K else np.zeros(0, np.int64)
        self._bstart = np.concatenate([[0], np.cumsum([len(bd) for bd in boundary])]).astype(np.int64)
        self._extend = [self._extend_plan(c) for c in range(K)]
        # plain-int copies for the per-supernode loops of factor/apply
        self._sizes = [
            (int(p[s]), int(b[s]), int(self.offset[s]), 3 * int(self.start[s]), int(self.zero_rows[s]))
            for s in range(K)
        ]
        nodes = np.arange(n)
        self._diagonal_index = self.scatter_index(nodes, nodes).reshape(n, 9)[:, [0, 4, 8]].reshape(-1)

    def _extend_plan(self, c: int) -> tuple | None:
        """How child ``c``'s update matrix (``b_c × b_c``, upper triangle valid) is added into its parent's front.

        The child's boundary dofs are in ascending elimination order, and so is the parent's front (its pivot, then
        its boundary), so the map of positions is increasing: the upper triangle lands in the parent's upper
        triangles (pivot ``S``, coupling ``C``, update ``E``), where the factorisation reads it. Returns
        ``(pivot and coupling part, update part)``, each either ``("slices", [(region, destination, source), …])``,
        one dense slice addition per pair of contiguous runs of the map (row run ≤ column run; runs split where the
        pivot ends), which is what separators ordered along themselves (:func:`_along`) give; or,
        when the runs are so many that a scatter is cheaper, ``("flat", (source, destination))``: flat positions of
        the entries in the update and in the parent's work vector (pivot and coupling) or its update block.
        ``None`` for a child without boundary.
        """
        s = int(self.parent[c])
        if s < 0 or self.boundary_size[c] == 0:
            return None
        p, b = int(self.pivot_size[s]), int(self.boundary_size[s])
        dofs = self.boundary_dofs[c]
        inside = dofs < 3 * int(self.stop[s])
        where = np.empty(len(dofs), dtype=np.int64)
        where[inside] = dofs[inside] - 3 * int(self.start[s])
        outside = self.boundary_dofs[s]
        k = np.searchsorted(outside, dofs[~inside])
        if np.any(k >= len(outside)) or np.any(outside[np.minimum(k, len(outside) - 1)] != dofs[~inside]):
            raise AssertionError(f"boundary of supernode {c} not inside its parent's front")  # a bug, not input
        where[~inside] = p + k
        cuts = np.flatnonzero((np.diff(where) != 1) | (where[1:] == p)) + 1
        first = np.concatenate([[0], cuts])
        last = np.concatenate([cuts, [len(where)]])
        runs = len(first)
        if runs * (runs + 1) // 2 <= max(4, len(where) ** 2 // 250):
            before, after = [], []
            for i in range(runs):
                r0, r1 = int(where[first[i]]), int(where[first[i]]) + int(last[i] - first[i])
                for j in range(i, runs):
                    c0, c1 = int(where[first[j]]), int(where[first[j]]) + int(last[j] - first[j])
                    src = (slice(int(first[i]), int(last[i])), slice(int(first[j]), int(last[j])))
                    if c1 <= p:
                        before.append((0, (slice(r0, r1), slice(c0, c1)), src))
                    elif r1 <= p:
                        before.append((1, (slice(r0, r1), slice(c0 - p, c1 - p)), src))
                    else:
                        after.append((2, (slice(r0 - p, r1 - p), slice(c0 - p, c1 - p)), src))
            return ("slices", before), ("slices", after)
        m = len(where)
        i, j = np.triu_indices(m)
        wi, wj = where[i], where[j]
        source = i * m + j
        destination = np.where(
            wj < p, wi * p + wj, np.where(wi < p, p * p + wi * b + (wj - p), (wi - p) * b + (wj - p))
        )
        late = wi >= p
        return ("flat", (source[~late], destination[~late])), ("flat", (source[late], destination[late]))

    # --- interface of BlockTridiagonal ----------------------------------------------------------------------------

    def scatter_index(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Flat storage index ``(m, 3, 3)`` of the 3×3 block (node ``rows[m]``, node ``cols[m]``).

        A block inside one supernode is stored in its pivot: both orientations are summed into the upper triangle
        (entry ``(i, j)`` of the matrix at ``(min(i, j), max(i, j))``), which :meth:`factor` halves off the
        diagonal, so the pivot is the symmetrised matrix. A block whose row node is eliminated first is stored in
        that supernode's coupling; the other orientation of such a block maps to ``storage_size`` (a dump slot).
        Raises ``ValueError`` for a pair of nodes the ordering was not built for.
        """
        rows = np.asarray(rows, dtype=np.int64).reshape(-1)
        cols = np.asarray(cols, dtype=np.int64).reshape(-1)
        sr, sc = self.supernode_of[rows], self.supernode_of[cols]
        same, below = sr == sc, sr < sc
        # the pair must be in the structure: the later node in the boundary of the earlier node's supernode
        first, later = np.minimum(sr, sc), np.where(below, cols, rows)
        keys = first * self.n_nodes + self.position[later]
        k = np.minimum(np.searchsorted(self._bkeys, keys), max(len(self._bkeys) - 1, 0))
        found = same | (self._bkeys[k] == keys if len(self._bkeys) else np.zeros(len(keys), dtype=bool))
        if not np.all(found):
            raise ValueError("coupling outside the factor's structure (ordering built from other pairs)")
        comp = np.arange(3)
        i = (3 * self.local[rows])[:, None, None] + comp[None, :, None]  # row and column within the front
        j = np.where(same, 3 * self.local[cols], self.pivot_size[sr] + 3 * (k - self._bstart[sr]))
        j = j[:, None, None] + comp[None, None, :]
        p = self.pivot_size[sr][:, None, None]
        b = self.boundary_size[sr][:, None, None]
        pivot = np.minimum(i, j) * p + np.maximum(i, j)
        coupling = p * p + i * b + (j - p)
        out = self.offset[sr][:, None, None] + np.where(same[:, None, None], pivot, coupling)
        out[~(same | below)] = self.storage_size
        return out

    def assemble(self, index: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Sum ``values`` into flat storage at ``index`` (same shapes); returns the storage vector."""
        return np.bincount(index.reshape(-1), weights=values.reshape(-1), minlength=self.storage_size + 1)

    def diagonal(self, storage: np.ndarray) -> np.ndarray:
        """The matrix diagonal in natural dof order (``3n``)."""
        return storage[self._diagonal_index]

    def dense(self, storage: np.ndarray) -> np.ndarray:
        """The symmetric matrix held in ``storage`` as a dense array, natural dof order (tests and checks)."""
        N = 3 * self.n_nodes
        out = np.zeros((N, N))
        for s, (p, b, off, lo, _) in enumerate(self._sizes):
            P = storage[off : off + p * p].reshape(p, p)
            C = storage[off + p * p : off + p * (p + b)].reshape(p, b)
            piv = self.order[lo : lo + p]
            bnd = self.order[self.boundary_dofs[s]]
            out[np.ix_(piv, piv)] += 0.5 * (P + P.T)
            out[np.ix_(piv, bnd)] += C
            out[np.ix_(bnd, piv)] += C.T
        return out

    def flops(self) -> float:
        """Floating-point operations of one factorisation with Cholesky pivots (potrf p³/3, trsm q²b, syrk qb² with
        ``q`` the pivot's rows coupled to its boundary)."""
        p = self.pivot_size.astype(np.float64)
        b = self.boundary_size.astype(np.float64)
        q = p - self.zero_rows
        return float(np.sum(p**3 / 3 + q * q * b + q * b * b))

    def factor(
        self,
        storage: np.ndarray,
        shift: np.ndarray | float = 0.0,
        inertia: bool = False,
        definite_only: bool = False,
    ) -> DissectionFactor:
        """Multifrontal block factorisation of ``A + diag(shift)`` over the supernode tree, kept for solves.

        For each supernode ``s`` in postorder, its *front* (one work vector: pivot ``S``, ``p × p``; coupling ``C``,
        ``p × b``; update ``E``, ``b × b``; upper triangles valid) is ``S = A_ss + shift`` and ``C = A_sB`` plus
        the children's updates there (:meth:`_extend_plan`). Then, as in :meth:`.linalg.BlockTridiagonal.factor`:

        * *Cholesky* (numpy's OpenBLAS, :mod:`.lapack`): ``S = Uᵀ U`` (``potrf``), ``W = U⁻ᵀ C`` (``trsm``),
          ``E = −Wᵀ W`` (``syrk``);
        * *inverse* (``S`` not positive definite, or no OpenBLAS routines): ``S⁻¹``, ``X = S⁻¹ C``, ``E = −Cᵀ X``;

        and the children's updates in ``E`` are added: ``E`` is what the parent receives.
        This is the block ``LDLᵀ`` factorisation by congruence, ``A = L diag(S_s) Lᵀ`` with the pivots in the
        nested-dissection order, so with ``inertia`` the negative eigenvalues of the matrix are those of the pivots
        together (Sylvester): a pivot that is not positive definite gets ``eigh``, its lowest eigenpair is kept for
        :meth:`DissectionFactor.negative_direction`. Raises ``np.linalg.LinAlgError`` for a singular or non-finite
        pivot; +inf on the diagonal (an infinitely stiff degree of freedom) gives that unknown 0, as the block
        tridiagonal factorisation does.

        With ``definite_only`` (and ``inertia``) the factorisation stops at the first pivot that is not positive
        definite, as :meth:`.linalg.BlockTridiagonal.factor` does: ``negative_pivots == 1`` (at least one),
        ``complete`` false, no solve (an exact Newton attempt away from a saddle only wants a definite matrix).
        """
        stop = inertia and definite_only
        try:
            return self._factor(storage, shift, inertia, backup=inertia and not stop, stop=stop)
        except _RestartError:  # a pivot was not positive definite and had not been kept: again, keeping every pivot
            return self._factor(storage, shift, inertia, backup=True)

    def _factor(
        self, storage: np.ndarray, shift: np.ndarray | float, inertia: bool, backup: bool, stop: bool = False
    ) -> DissectionFactor:
        """:meth:`factor`; ``backup``: copy each pivot before ``potrf`` (which overwrites it when it fails), else
        raise :class:`_RestartError` at the first pivot that is not positive definite; ``stop``: return an
        incomplete factor there instead (``definite_only``)."""
        shift_vec = np.broadcast_to(np.asarray(shift, dtype=np.float64), (3 * self.n_nodes,))[self.order]
        lib = lapack.routines()
        K = len(self.supernodes)
        chols: list[np.ndarray | None] = [None] * K
        inverses: list[np.ndarray | None] = [None] * K
        couplings: list[np.ndarray | None] = [None] * K
        first_row = [0] * K
        fronts: list[tuple | None] = [None] * K
        negative = 0
        negatives: list[tuple[int, np.ndarray, np.ndarray]] = []

        def front(s: int) -> tuple:
            """The front of ``s``: work vector (pivot ``S`` and coupling ``C``) assembled from the storage and the
            shift, and a zero update block ``E``; ``(buf, S, C, E)``."""
            p, b, off, lo, _ = self._sizes[s]
            pp, pb = p * p, p * b
            buf = np.empty(pp + pb)
            np.multiply(storage[off : off + pp], 0.5, out=buf[:pp])  # both orientations were summed there
            np.add(storage[off : off + pp : p + 1], shift_vec[lo : lo + p], out=buf[: pp : p + 1])  # not twice
            buf[pp:] = storage[off + pp : off + pp + pb]
            return buf, buf[:pp].reshape(p, p), buf[pp:].reshape(p, b), np.zeros((b, b))

        def stopped() -> DissectionFactor:
            out = DissectionFactor(self, chols, inverses, couplings, first_row, lib)
            out.negative_pivots, out.complete = 1, False
            return out

        def push(c: int, U: np.ndarray) -> None:
            """Add the update ``U`` of ``c`` into its parent's front (made now if it is the first child to come),
            while ``U`` is still in the cache."""
            plan = self._extend[c]
            if plan is None:
                return
            s = int(self.parent[c])
            if fronts[s] is None:
                fronts[s] = front(s)
            buf, *regions = fronts[s]
            for flat, (kind, ops) in zip((buf, regions[2].reshape(-1)), plan, strict=True):
                if kind == "slices":
                    for region, destination, source in ops:
                        regions[region][destination] += U[source]
                else:
                    flat[ops[1]] += U.reshape(-1)[ops[0]]

        for s in range(K):
            buf, S, C, E = fronts[s] if fronts[s] is not None else front(s)
            fronts[s] = None
            b = C.shape[1]
            if lib is not None:
                kept = S.copy() if backup else None
                if lib.cholesky(S):
                    # a NaN anywhere in the pivot reaches the diagonal of U; +inf there is kept (see above)
                    if np.isnan(np.diagonal(S)).any():
                        raise np.linalg.LinAlgError(f"non-finite Cholesky factor of supernode {s}")
                    k = self._sizes[s][4]
                    if b:
                        if k < C.shape[0]:  # rows above k of C, so of W, are zero
                            lib.solve_upper_transposed(S[k:, k:], C[k:])
                            lib.subtract_gram(E, C[k:])
                        push(s, E)
                        couplings[s] = C[k:]
                    chols[s], first_row[s] = S, k
                    continue
                if stop:
                    return stopped()
                if kept is None:
                    raise _RestartError
                S = kept
                positive_definite = False
            else:
                positive_definite = True
            Sf = np.triu(S)
            Sf += np.triu(S, 1).T
            if inertia and positive_definite:
                positive_definite = is_positive_definite(Sf)
            if inertia and not positive_definite:
                if stop:
                    return stopped()
                values, vectors = negative_eigenpairs(Sf)
                negative += len(values)
                if len(values):
                    negatives.append((s, values, vectors))
            Sinv = inverse_pivot(Sf, f"supernode {s}")
            inverses[s] = Sinv
            if b:
                k = self._sizes[s][4]  # rows above k of C are zero
                X = Sinv[:, k:] @ C[k:]
                E -= C[k:].T @ X[k:]
                push(s, E)
                couplings[s] = X
        out = DissectionFactor(self, chols, inverses, couplings, first_row, lib)
        out.negative_pivots = negative if inertia else None
        out.negative_pairs = negatives
        return out

    def solve(self, storage: np.ndarray, rhs: np.ndarray, shift: np.ndarray | float = 0.0) -> np.ndarray:
        """Solve ``(A + diag(shift)) x = rhs`` (natural dof order, length ``3n``)."""
        return self.factor(storage, shift).apply(rhs)


class DissectionFactor:
    """A multifrontal factorisation (see :meth:`NestedDissection.factor`); :meth:`apply` solves with it.

    Per supernode ``s`` either ``chols[s]`` (``U_s``, ``S_s = U_sᵀ U_s``, in its upper triangle) or ``inverses[s]``
    (``S_s⁻¹``) is set; ``couplings[s]`` (``None`` without boundary) holds the rows from ``first_row[s]`` on of
    ``W_s = U_s⁻ᵀ C_s`` (the rows above are zero) or all of ``X_s = S_s⁻¹ C_s`` (``first_row[s]`` 0), ``C_s`` the
    coupling of the pivot to its boundary in the front.
    """

    def __init__(self, structure: NestedDissection, chols, inverses, couplings, first_row, lib: lapack.OpenBLAS | None):
        self.structure = structure
        self.chols, self.inverses, self.couplings, self.first_row = chols, inverses, couplings, first_row
        self.lib = lib
        self.size = 3 * structure.n_nodes
        self.negative_pivots: int | None = None
        """Number of negative eigenvalues of the factored matrix (``None`` when not computed)."""
        self.negative_pairs: list[tuple[int, np.ndarray, np.ndarray]] = []
        """Every negative eigenpair of the pivots: ``(supernode, eigenvalues, eigenvectors as columns)``."""
        self.complete = True
        """False for a factorisation stopped at its first indefinite pivot (``definite_only``): it cannot solve."""

    @property
    def lowest_pivot(self) -> tuple[float, int, np.ndarray | None]:
        """``(eigenvalue, supernode, eigenvector)`` of the most negative pivot eigenvalue (``(0.0, −1, None)``: none),
        from :attr:`negative_pairs`."""
        if not self.negative_pairs:
            return (0.0, -1, None)
        s, values, vectors = min(self.negative_pairs, key=lambda pair: pair[1][0])
        return (float(values[0]), s, vectors[:, 0])

    def apply(self, rhs: np.ndarray) -> np.ndarray:
        """``(A + diag(shift))⁻¹ rhs`` for a flat ``3n`` vector.

        In elimination order, forward over the supernodes: ``y_s = U_s⁻ᵀ r_s`` and ``r_B −= W_sᵀ y_s`` (or
        ``r_B −= X_sᵀ r_s`` and ``y_s = S_s⁻¹ r_s``); back in reverse: ``x_s = U_s⁻¹ (y_s − W_s x_B)`` (or
        ``y_s − X_s x_B``). The ancestors' entries ``B`` are gathered and scattered by index, a contiguous
        range is the pivot's.
        """
        st = self.structure
        r = np.asarray(rhs, dtype=np.float64)[st.order]
        K = len(self.chols)
        lo, hi, bd = 3 * st.start, 3 * st.stop, st.boundary_dofs
        lib = self.lib
        for s in range(K):
            g = r[lo[s] : hi[s]]
            U, Cp, k = self.chols[s], self.couplings[s], self.first_row[s]
            if U is not None:
                lib.solve_upper_vector(U, g, transpose=True)
                if Cp is not None:
                    r[bd[s]] -= g[k:] @ Cp
            else:
                if Cp is not None:
                    r[bd[s]] -= g @ Cp
                g[...] = self.inverses[s] @ g
        for s in range(K - 1, -1, -1):
            g = r[lo[s] : hi[s]]
            U, Cp, k = self.chols[s], self.couplings[s], self.first_row[s]
            if Cp is not None:
                g[k:] -= Cp @ r[bd[s]]
            if U is not None:
                lib.solve_upper_vector(U, g)
        out = np.empty(self.size)
        out[st.order] = r
        return out

    def negative_subspace_direction(self, chooser: np.ndarray) -> np.ndarray | None:
        """``w = L⁻ᵀ z`` with ``z`` a combination of every negative eigenvector of every pivot, each with the sign
        ``chooser`` (natural dof order) gives it and weight ``λ / λ_min``: ``wᵀ A w = Σ c² λ < 0``, along all the
        unstable modes at once."""
        if not self.negative_pairs:
            return None
        st = self.structure
        ch = np.asarray(chooser, dtype=np.float64)[st.order]
        w = np.zeros(self.size)
        lowest = self.lowest_pivot[0]
        for s, vals, vecs in self.negative_pairs:
            part = ch[3 * st.start[s] : 3 * st.stop[s]] @ vecs
            w[3 * st.start[s] : 3 * st.stop[s]] += vecs @ (np.where(part < 0, -1.0, 1.0) * vals / lowest)
        return self._back_substitute(w, [s for s, _, _ in self.negative_pairs])

    def negative_direction(self) -> np.ndarray | None:
        """A direction ``w`` with ``wᵀ A w = λ_min(S_k) < 0`` (natural dof order), or ``None`` if A is not indefinite.

        ``w = L⁻ᵀ z`` with ``z`` the lowest eigenvector of the pivot ``S_k`` (zero elsewhere), so ``wᵀ A w = zᵀ S_k
        z``. ``Lᵀ`` is unit block upper triangular with blocks ``X_s = S_s⁻¹ C_s`` (row ``s``, columns ``B_s``), so
        back substitution gives ``w_s = −X_s w_{B_s}`` for the supernodes before ``k``, 0 after it. ``w_{B_s}`` is
        nonzero only if ``B_s`` meets the support found so far, which starts at ``k``; ``B_s`` lies in ancestors of
        ``s``, so the support is ``k`` and its descendants: the back substitution runs over the subtree of ``k``
        only (a contiguous range in postorder).
        """
        value, k, z = self.lowest_pivot
        if k < 0 or z is None or value >= 0:
            return None
        st = self.structure
        w = np.zeros(self.size)
        w[3 * st.start[k] : 3 * st.stop[k]] = z
        return self._back_substitute(w, [k])

    def _back_substitute(self, w: np.ndarray, seeds: list[int]) -> np.ndarray:
        """``L⁻ᵀ z`` in natural dof order, for ``z`` (in ``w``, elimination order, overwritten) nonzero on the
        supernodes ``seeds`` only: ``w_s = z_s − X_s w_{B_s}`` (``−U_s⁻¹ W_s w_{B_s}`` for a Cholesky pivot, whose
        ``z_s`` is 0) from the highest seed down, over the seeds' subtrees only (see :meth:`negative_direction`:
        elsewhere ``w_{B_s}`` is 0)."""
        st = self.structure
        top = max(seeds)
        for s in range(top - 1, min(int(st.first_descendant[k]) for k in seeds) - 1, -1):
            Cp = self.couplings[s]
            if Cp is None:
                continue
            g = w[3 * st.start[s] : 3 * st.stop[s]]
            g[self.first_row[s] :] -= Cp @ w[st.boundary_dofs[s]]
            if self.chols[s] is not None:
                self.lib.solve_upper_vector(self.chols[s], g)
        out = np.empty(self.size)
        out[st.order] = w
        return out
