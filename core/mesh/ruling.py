"""Ruling-aware edge swaps (paper §3.3), on a ``bmesh``.

The paper assumes the folded crease stays planar with a constant fold angle, so the rulings are orthogonal to the
curved crease in the flat pattern (τ = 0, α′ = 0 in Tachi's relations). A facet edge V_A–V_C is scored by how
well it bisects the crease polyline at its ends: at endpoint P with crease-pattern neighbours X1, X2 (the two
segments met by turning around P inside the face, one each way), the angles θ_a = ∠(PX2, PQ) and θ_b = ∠(PQ, PX1)
give (θ_a − θ_b)², zero for the discrete bisector. Following the authors' code (ground-truth §1.2):

* only *curve* segments (``edge_from_curve``) score; an endpoint whose two segments are not both curve segments does
  not score (so border endpoints never do); a single scoring endpoint is doubled; no scoring endpoint = ∞;
* a swap is a candidate when the edge is neither crease nor border (not a pattern segment), its quad is strictly
  convex, the new endpoints V_B, V_D each have at most three facet edges in that crease-pattern face before the
  swap (paper condition 2, counted per face as the authors intended), the new edge does not exist yet, the
  new cost is strictly lower, and (our addition, not in the paper) the two new triangles have no corner below
  ``min(SWAP_MIN_CORNER_DEG, smallest corner of the two old ones)``: no sliver beyond what the pattern forces;
* the candidate with the smallest new cost is swapped, repeatedly, until none is left.

Then :func:`.squash.squash_flips` flips away the caps the fold could press flat (not in the paper; decided on the same
lists, applied with the swaps).

Because every swap strictly lowers the total cost (∞ counted first), the loop terminates. The loop is a priority
queue with lazy re-evaluation: after a swap only the edges opposite its four vertices in the triangles around
them are re-scored (the valence, the quads and the existing edges change only there).

Speed: the swaps are *decided* on a plain half-edge structure (a dict from directed edge to triangle, Python lists),
with every edge's cost, quad, convexity and valence test evaluated for the whole mesh at once in numpy at the start
and the heap built with ``heapify``; only the few edges around each accepted swap are re-evaluated one by one. The
accepted swaps are then *applied* to a ``bmesh`` built once, with ``bmesh.ops.rotate_edges``: one call per level
of swaps whose quads share no triangle (disjoint rotations commute; the levels keep the order of dependent swaps),
edges found through ``bm.edges.get`` on the vertex pair. Each rotation is checked to give the expected edge and
the final BMesh triangles are checked to equal the decided ones. The returned triangles keep their input rows
(the two triangles of a flipped quad stay in the quad's two rows), independent of bmesh's element order.

The endpoint angles depend only on which *wedge* between consecutive pattern segments at P the edge lies in, which
no swap changes (pattern segments are never swapped). So the walk around P inside the face is replaced by a lookup
among P's pattern segments sorted by angle: the same X1, X2 as the walk, in O(log deg).
"""

from __future__ import annotations

import bisect
import heapq
import math
from collections.abc import Generator
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import load_bpy, run_to_end
from .squash import SQUASH_STRAIN, squash_flips
from .triangulate import _orient2, orient

_INF = math.inf

SWAP_MIN_CORNER_DEG = 2.0
"""A swap may not leave a triangle corner below ``min(this, the smallest corner of the two triangles it replaces)``.

The ruling score alone happily trades a fat pair of triangles for a sliver (on the fixtures, swaps halved the CDT's
smallest corner: ``single_curve`` 4.1° → 2.1°); a corner the solver can squash to a line puts a kink into the
face-angle energy. The CDT maximises the smallest corner over every triangulation of the segments, so with this rule
the ruling mesh's smallest corner is at least ``min(CDT's smallest corner, SWAP_MIN_CORNER_DEG)``: swaps still
align facets with the rulings wherever that costs no corner below 2°, and never make a sliver worse. 2° keeps every
swap of the examples and all but one of ``Carved_Cylinder``'s 213 (which made a 1.95° corner); 3° refused 12 on
``single_curve`` and 16 on ``Carved_Cylinder``, raising the mean warp by 0.1–0.2° (worse rulings) for corners the
solver handles well. Corners under 1° are what stalls it (issue 12)."""

_MIN_CORNER_RAD = math.radians(SWAP_MIN_CORNER_DEG)


@dataclass
class SwapResult:
    """Triangles after the swaps (CCW), their crease-pattern face, and what the loop did."""

    triangles: np.ndarray
    triangle_face: np.ndarray
    swaps: int
    convexity_checks: int
    rejected_valence: int
    rejected_sliver: int = 0
    """Candidates refused because the swap would leave a corner below :data:`SWAP_MIN_CORNER_DEG` and below the
    quad's smallest corner before the swap."""
    squash_flips: int = 0
    """Of ``swaps``, the flips after the ruling swaps that removed triangles the fold could press flat
    (:mod:`.squash`)."""


class EndpointScorer:
    """Scores an edge endpoint by the bisector criterion, from the pattern segments around each vertex.

    ``segments`` are the pattern segments as mesh vertex pairs, ``curve`` whether each discretises a curve.
    """

    def __init__(self, vertices: np.ndarray, segments: np.ndarray, curve: np.ndarray) -> None:
        self.vertices = np.asarray(vertices, dtype=float)
        n = len(self.vertices)
        ends = np.concatenate([segments, segments[:, ::-1]])
        flags = np.concatenate([curve, curve])
        d = self.vertices[ends[:, 1]] - self.vertices[ends[:, 0]]
        # math.atan2 (libm), as for the edge directions in wedge/_endpoints: numpy's arctan2 differs from it in the
        # last bit and between numpy versions (SVML in 1.26 on AVX-512), and the wedge search compares the two
        ang = np.fromiter(map(math.atan2, d[:, 1].tolist(), d[:, 0].tolist()), dtype=float, count=len(d))
        order = np.lexsort((ang, ends[:, 0]))
        ends, flags, ang = ends[order], flags[order], ang[order]
        start = np.searchsorted(ends[:, 0], np.arange(n + 1))
        self._angles = [ang[start[v] : start[v + 1]].tolist() for v in range(n)]
        self._flags = [flags[start[v] : start[v + 1]].tolist() for v in range(n)]
        self._xy = self.vertices.tolist()
        self._cost: dict[tuple[int, int], float] = {}
        deg = np.diff(start)
        width = max(1, int(deg.max()) if n else 1)
        slot = np.arange(len(ang)) - np.repeat(start[:-1], deg)
        self._deg = deg
        self._start = start[:-1]
        self._ang_sorted = ang
        self._flag_sorted = flags
        # per-vertex segment angles padded with +inf: the wedge of a direction is found by counting smaller angles
        self._ang_table = np.full((n, width), np.inf)
        self._ang_table[ends[:, 0], slot] = ang

    def wedge(self, p: int, q: int) -> tuple[float, float, bool]:
        """``(θ_a, θ_b, scores)`` for edge p→q: angles from the clockwise-previous segment to pq and from pq to the
        counter-clockwise-next one; ``scores`` is False unless both are distinct curve segments."""
        angs = self._angles[p]
        k = len(angs)
        if k == 0:
            return 0.0, 0.0, False
        (px, py), (qx, qy) = self._xy[p], self._xy[q]
        a = math.atan2(qy - py, qx - px)
        i = bisect.bisect_left(angs, a)
        nxt, prv = i % k, (i - 1) % k
        two_pi = 2.0 * math.pi
        theta_a = (a - angs[prv]) % two_pi
        theta_b = (angs[nxt] - a) % two_pi
        scores = k >= 2 and bool(self._flags[p][nxt]) and bool(self._flags[p][prv])
        return theta_a, theta_b, scores

    def _endpoints(self, p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`endpoint` for arrays of edges p→q: ``(score, scores)`` with the same floating-point operations
        as the scalar path (``math.atan2`` for the edge direction, as :meth:`wedge`), so the values are identical."""
        xy = self.vertices
        d = xy[q] - xy[p]
        a = np.fromiter(map(math.atan2, d[:, 1].tolist(), d[:, 0].tolist()), dtype=float, count=len(p))
        k = self._deg[p]
        has = k > 0
        kk = np.maximum(k, 1)
        i = np.count_nonzero(self._ang_table[p] < a[:, None], axis=1)  # = bisect_left over the sorted angles
        nxt, prv = self._start[p] + i % kk, self._start[p] + (i - 1) % kk
        nxt, prv = np.where(has, nxt, 0), np.where(has, prv, 0)
        two_pi = 2.0 * math.pi
        if len(self._ang_sorted):
            theta_a = np.mod(a - self._ang_sorted[prv], two_pi)
            theta_b = np.mod(self._ang_sorted[nxt] - a, two_pi)
            scores = (k >= 2) & self._flag_sorted[nxt] & self._flag_sorted[prv]
        else:
            theta_a = theta_b = np.zeros(len(p))
            scores = np.zeros(len(p), dtype=bool)
        # Python's float ** 2 (libm pow) can differ from numpy's square in the last bit: square the scalar way, so
        # batch and scalar costs are identical
        diff = (theta_a - theta_b).tolist()
        return np.fromiter((x**2 for x in diff), dtype=float, count=len(diff)), scores

    def costs(self, p: np.ndarray, q: np.ndarray) -> np.ndarray:
        """:meth:`cost` of many edges at once (vectorised; fills the same cache, identical values)."""
        p = np.asarray(p, dtype=np.int64).reshape(-1)
        q = np.asarray(q, dtype=np.int64).reshape(-1)
        if len(p) == 0:
            return np.zeros(0)
        sp, okp = self._endpoints(p, q)
        sq, okq = self._endpoints(q, p)
        value = np.where(okp & okq, sp + sq, np.where(okp, 2.0 * sp, np.where(okq, 2.0 * sq, _INF)))
        # batch and scalar values are bit-identical (tested), so overwriting cached entries changes nothing
        keys = zip(np.minimum(p, q).tolist(), np.maximum(p, q).tolist(), strict=True)
        self._cost.update(zip(keys, value.tolist(), strict=True))
        return value

    def endpoint(self, p: int, q: int) -> float | None:
        """(θ_a − θ_b)² at endpoint p of edge pq, or None when p does not score."""
        ta, tb, ok = self.wedge(p, q)
        return (ta - tb) ** 2 if ok else None

    def cost(self, p: int, q: int) -> float:
        """E of edge pq: sum of both scores, a single score doubled, ∞ when neither endpoint scores."""
        key = (p, q) if p < q else (q, p)
        cached = self._cost.get(key)
        if cached is not None:
            return cached
        sp, sq = self.endpoint(p, q), self.endpoint(q, p)
        if sp is None and sq is None:
            value = _INF
        elif sp is None:
            value = 2.0 * sq
        elif sq is None:
            value = 2.0 * sp
        else:
            value = sp + sq
        self._cost[key] = value
        return value


def _corner(p: list[float], q: list[float], r: list[float]) -> float:
    """Corner angle at p of triangle (p, q, r), radians."""
    ux, uy, wx, wy = q[0] - p[0], q[1] - p[1], r[0] - p[0], r[1] - p[1]
    return math.atan2(abs(ux * wy - uy * wx), ux * wx + uy * wy)


def _min_corner(p: list[float], q: list[float], r: list[float]) -> float:
    """Smallest corner angle of triangle (p, q, r), radians."""
    return min(_corner(p, q, r), _corner(q, r, p), _corner(r, p, q))


def _keeps_corners(pa: list[float], pb: list[float], pc: list[float], pd: list[float]) -> bool:
    """Whether swapping diagonal ac of quad a, d, c, b for bd respects :data:`SWAP_MIN_CORNER_DEG`."""
    old = min(_min_corner(pa, pc, pb), _min_corner(pc, pa, pd))
    new = min(_min_corner(pa, pd, pb), _min_corner(pd, pc, pb))
    return new >= min(old, _MIN_CORNER_RAD)


def _strictly_crosses(o1, o2, eps):
    """Segments' end orientations o1, o2 on strictly opposite sides (beyond ``eps``)."""
    return ((o1 > eps) & (o2 < -eps)) | ((o1 < -eps) & (o2 > eps))


def _segment_codes(segments: np.ndarray, n: int) -> np.ndarray:
    """The pattern segments as sorted unique undirected-edge codes ``min·n + max`` (never swapped or flipped)."""
    return np.unique(np.sort(segments, axis=1) @ np.array([n, 1], dtype=np.int64))


def _half_edge_arrays(triangles: np.ndarray, n: int) -> tuple[np.ndarray, ...]:
    """Half-edges h = 3·triangle + k, from corner k to corner k + 1: ``(org, dst, opp, code, twin)``, with ``opp``
    the triangle's third vertex, ``code`` the directed-edge code ``org·n + dst`` and ``twin`` the opposite
    half-edge (−1 on the hull)."""
    org = triangles.reshape(-1)
    dst = np.roll(triangles, -1, axis=1).reshape(-1)
    opp = np.roll(triangles, -2, axis=1).reshape(-1)
    code = org * n + dst
    order = np.argsort(code)
    twin_code = dst * n + org
    pos = np.clip(np.searchsorted(code[order], twin_code), 0, len(code) - 1)
    twin = np.where(code[order][pos] == twin_code, order[pos], -1)
    return org, dst, opp, code, twin


class _SwapLoop:
    """The greedy loop's mutable state: a half-edge structure over plain Python containers, the facet valence per
    (vertex, crease-pattern face), the identity of every edge instance, and the priority queue of candidates.

    Keys are integers: a directed edge x→y is ``x·n + y``, an undirected edge the code of (min, max) (so codes sort
    like the vertex pairs, and heap ties break exactly as on pairs), a (vertex, face) pair ``v·n_faces + f``.
    """

    def __init__(
        self,
        vertices: np.ndarray,
        triangles: np.ndarray,
        triangle_face: np.ndarray,
        segments: np.ndarray,
        scorer: EndpointScorer,
        max_valence: int,
    ) -> None:
        n = self.n = len(vertices)
        t = len(triangles)
        self.n_faces = int(triangle_face.max()) + 1 if t else 1
        self.vertices, self.scorer, self.max_valence = vertices, scorer, max_valence
        self.xy = vertices.tolist()
        scale2 = float(np.sum((vertices.max(0) - vertices.min(0)) ** 2)) or 1.0
        self.eps = 1e-12 * scale2
        self.seg_code = _segment_codes(segments, n)
        self.constrained = set(self.seg_code.tolist())
        self.he = _half_edge_arrays(triangles, n)
        org, dst, _opp, code, twin = self.he
        is_seg = np.isin(np.minimum(org, dst) * n + np.maximum(org, dst), self.seg_code)
        self.face_of_he = np.repeat(triangle_face, 3)
        # facet edges = interior non-segment edges, each once (through its half-edge with org < dst)
        self.facet_once = (twin >= 0) & ~is_seg & (org < dst)
        self.n_edges = int(np.count_nonzero(twin < 0)) + int(np.count_nonzero(twin >= 0)) // 2
        vf = np.concatenate([org[self.facet_once], dst[self.facet_once]]) * self.n_faces + np.tile(
            self.face_of_he[self.facet_once], 2
        )
        self.vf_code, self.vf_count = np.unique(vf, return_counts=True)
        self.valence: dict[int, int] = dict(zip(self.vf_code.tolist(), self.vf_count.tolist(), strict=True))
        self.stats = {"convex": 0, "valence": 0, "sliver": 0}
        # the mutable half-edge structure: directed edge -> triangle; an id per edge instance (a flipped edge dies)
        self.tris = triangles.tolist()
        self.tface = triangle_face.tolist()
        self.owner: dict[int, int] = dict(zip(code.tolist(), (np.arange(3 * t) // 3).tolist(), strict=True))
        by_vertex = np.argsort(org, kind="stable")
        self._fan_start = np.searchsorted(org[by_vertex], np.arange(n + 1)).tolist()
        self._fan_tris = (by_vertex // 3).tolist()
        self.fans: dict[int, set[int]] = {}  # vertex -> its triangles, materialised on first use
        self.edge_id: dict[int, int] = {}
        self.next_id = 0
        self.heap: list[tuple[float, int, int, int, int]] = []
        self.counter = 0

    def fan(self, v: int) -> set[int]:
        """The triangles around ``v`` (materialised before any change to them)."""
        s = self.fans.get(v)
        if s is None:
            s = self.fans[v] = set(self._fan_tris[self._fan_start[v] : self._fan_start[v + 1]])
        return s

    def instance(self, key: int) -> int:
        """The id of the current instance of edge ``key`` (a new id once the edge is flipped away and back)."""
        eid = self.edge_id.get(key)
        if eid is None:
            eid = self.edge_id[key] = self.next_id
            self.next_id += 1
        return eid

    def push(self, cost: float, new_key: int, key: int, eid: int) -> None:
        self.counter += 1
        heapq.heappush(self.heap, (cost, new_key, key, self.counter, eid))

    def queue_initial(self) -> None:
        """Evaluate every facet edge at once (the same tests as :meth:`evaluate`, vectorised) and heapify."""
        n, vertices, eps, stats = self.n, self.vertices, self.eps, self.stats
        org, dst, opp, code, twin = self.he
        cand = np.flatnonzero(self.facet_once)
        a_, c_ = org[cand], dst[cand]
        b_, d_ = opp[cand], opp[twin[cand]]
        nlo, nhi = np.minimum(b_, d_), np.maximum(b_, d_)
        new_cost = self.scorer.costs(b_, d_)
        old_cost = self.scorer.costs(a_, c_)
        ok = ~np.isin(nlo * n + nhi, self.seg_code)
        ok &= new_cost < old_cost
        stats["convex"] += int(np.count_nonzero(ok))
        pa, pb, pc, pd = vertices[a_], vertices[b_], vertices[c_], vertices[d_]
        ok &= _strictly_crosses(orient(pb, pd, pa), orient(pb, pd, pc), eps)
        ok &= _strictly_crosses(orient(pa, pc, pb), orient(pa, pc, pd), eps)
        f_ = self.face_of_he[cand]
        vb = _lookup(self.vf_code, self.vf_count, b_ * self.n_faces + f_)
        vd = _lookup(self.vf_code, self.vf_count, d_ * self.n_faces + f_)
        too_many = ok & ((vb > self.max_valence) | (vd > self.max_valence))
        stats["valence"] += int(np.count_nonzero(too_many))
        ok &= ~too_many
        ok &= ~np.isin(b_ * n + d_, code) & ~np.isin(d_ * n + b_, code)
        xy = self.xy
        for k in np.flatnonzero(ok).tolist():  # the corner test in scalar form, bit-identical to :meth:`evaluate`
            if not _keeps_corners(xy[a_[k]], xy[b_[k]], xy[c_[k]], xy[d_[k]]):
                ok[k] = False
                stats["sliver"] += 1
        for k in np.flatnonzero(ok).tolist():
            key = int(a_[k]) * n + int(c_[k])
            self.counter += 1
            self.heap.append((float(new_cost[k]), int(nlo[k]) * n + int(nhi[k]), key, self.counter, self.instance(key)))
        heapq.heapify(self.heap)

    def evaluate(self, a: int, c: int) -> tuple[float, int] | None:
        """The new cost if edge ac (a < c) is a swap candidate, with the new edge's code; None otherwise."""
        n, owner, tris, constrained = self.n, self.owner, self.tris, self.constrained
        if a * n + c in constrained:
            return None
        t1, t2 = owner.get(a * n + c), owner.get(c * n + a)
        if t1 is None or t2 is None:
            return None
        tr1, tr2 = tris[t1], tris[t2]
        b = tr1[0] + tr1[1] + tr1[2] - a - c
        d = tr2[0] + tr2[1] + tr2[2] - a - c
        bd = (b, d) if b < d else (d, b)
        key = bd[0] * n + bd[1]
        if key in constrained:
            return None
        cost_cache = self.scorer._cost
        new = cost_cache.get(bd)
        if new is None:
            new = self.scorer.cost(b, d)
        old = cost_cache.get((a, c))
        if old is None:
            old = self.scorer.cost(a, c)
        if not new < old:
            return None
        self.stats["convex"] += 1
        xy, eps = self.xy, self.eps
        pa, pb, pc, pd = xy[a], xy[b], xy[c], xy[d]
        o1, o2 = _orient2(pb, pd, pa), _orient2(pb, pd, pc)
        o3, o4 = _orient2(pa, pc, pb), _orient2(pa, pc, pd)
        if not ((o1 > eps and o2 < -eps) or (o1 < -eps and o2 > eps)):
            return None
        if not ((o3 > eps and o4 < -eps) or (o3 < -eps and o4 > eps)):
            return None
        f, n_faces, valence = self.tface[t1], self.n_faces, self.valence
        if valence.get(b * n_faces + f, 0) > self.max_valence or valence.get(d * n_faces + f, 0) > self.max_valence:
            self.stats["valence"] += 1
            return None
        if b * n + d in owner or d * n + b in owner:
            return None
        if not _keeps_corners(pa, pb, pc, pd):
            self.stats["sliver"] += 1
            return None
        return new, key

    def flip(self, a: int, c: int, new_key: int) -> tuple[int, ...]:
        """Swap edge ac for bd in the half-edge structure, fans, edge instances and valences; the swap record."""
        n, owner, tris, tface = self.n, self.owner, self.tris, self.tface
        t1, t2 = owner[a * n + c], owner[c * n + a]
        tr1, tr2 = tris[t1], tris[t2]
        b = tr1[0] + tr1[1] + tr1[2] - a - c
        d = tr2[0] + tr2[1] + tr2[2] - a - c
        f = tface[t1]
        # t1 = (a, c, b) and t2 = (c, a, d), CCW; the quad is a, d, c, b; the new triangles (a, d, b), (d, c, b)
        for x, y, z in (tr1, tr2):
            del owner[x * n + y], owner[y * n + z], owner[z * n + x]
        tris[t1], tris[t2] = [a, d, b], [d, c, b]
        for ti in (t1, t2):
            x, y, z = tris[ti]
            owner[x * n + y] = ti
            owner[y * n + z] = ti
            owner[z * n + x] = ti
        self.fan(a).discard(t2)
        self.fan(c).discard(t1)
        self.fan(b).add(t2)
        self.fan(d).add(t1)
        del self.edge_id[a * n + c]
        self.instance(new_key)
        valence, n_faces = self.valence, self.n_faces
        valence[a * n_faces + f] -= 1
        valence[c * n_faces + f] -= 1
        valence[b * n_faces + f] = valence.get(b * n_faces + f, 0) + 1
        valence[d * n_faces + f] = valence.get(d * n_faces + f, 0) + 1
        return a, c, b, d, t1, t2, f

    def requeue_around(self, quad: tuple[int, int, int, int]) -> None:
        """Re-evaluate what a swap can have changed: an edge's evaluation depends on its two triangles, on the facet
        valence of its two opposite vertices and on whether the edge between them exists. Triangles changed only in
        the quad, valence only at its four vertices, and the only edge created/removed joins b, d / a, c; so the
        edges to re-evaluate are those opposite a, b, c or d in a triangle around it (this includes the quad's five
        edges). Re-evaluating more would only queue duplicates of entries already in the heap."""
        n, tris = self.n, self.tris
        seen: set[int] = set()
        for vi in quad:
            for ti in self.fan(vi):
                x, y, z = tris[ti]
                p, q = (y, z) if vi == x else ((z, x) if vi == y else (x, y))
                if p > q:
                    p, q = q, p
                e = p * n + q
                if e in seen:
                    continue
                seen.add(e)
                r = self.evaluate(p, q)
                if r is not None:
                    self.push(r[0], r[1], e, self.instance(e))


SWAP_UNIT_POPS = 600
"""Queue entries the swap loop takes per unit of work (:func:`ruling_swaps_steps`): ~20–40 ms on this machine.

A Blender job runs one unit per slice. As one unit, the swaps of a curve drawn as a 1 mm polyline (Carved_Cylinder,
3,314 faces, 1,446 swaps) took 0.5–0.7 s: Blender froze for that long."""

SWAP_UNIT_LEVELS = 400
"""Swaps applied to the ``bmesh`` per unit of work (whole levels of independent rotations)."""


def _decide_swaps_steps(
    vertices: np.ndarray,
    triangles: np.ndarray,
    triangle_face: np.ndarray,
    segments: np.ndarray,
    scorer: EndpointScorer,
    max_valence: int,
    max_swaps: int | None,
) -> Generator[str, None, tuple[list[tuple[int, ...]], list[list[int]], dict[str, int]]]:
    """Run the greedy swap loop on a half-edge structure, in units of :data:`SWAP_UNIT_POPS` queue entries (yields
    the unit's name); return the swaps ``(a, c, b, d, t1, t2, f)`` in order (edge ac becomes bd; t1, t2 the two
    triangle slots of the quad, f its crease-pattern face), the final triangles (CCW, same slots as the input) and
    loop statistics.

    Steps: evaluate every facet edge at once and queue the candidates by new cost; pop the cheapest, skip it if its
    edge was flipped away, re-queue it if its value changed, otherwise swap and re-evaluate the edges around.
    """
    loop = _SwapLoop(vertices, triangles, triangle_face, segments, scorer, max_valence)
    loop.queue_initial()
    yield "swap candidates scored"
    n, heap = loop.n, loop.heap
    swaps: list[tuple[int, ...]] = []
    cap = max_swaps if max_swaps is not None else 100 * max(1, loop.n_edges)
    pops = 0
    while heap and len(swaps) < cap:
        pops += 1
        if pops % SWAP_UNIT_POPS == 0:
            yield "ruling swaps"
        cost_q, key, old, _n, eid = heapq.heappop(heap)
        if loop.edge_id.get(old) != eid:  # the edge this entry was queued for has been flipped away
            continue
        a, c = divmod(old, n)
        r = loop.evaluate(a, c)
        if r is None:
            continue
        if r[0] != cost_q:  # stale entry: its value changed since it was queued
            loop.push(r[0], r[1], old, eid)
            continue
        sw = loop.flip(a, c, key)
        swaps.append(sw)
        loop.requeue_around((a, c, sw[2], sw[3]))
    return swaps, loop.tris, loop.stats


def _lookup(codes: np.ndarray, counts: np.ndarray, query: np.ndarray) -> np.ndarray:
    """``counts`` of each ``query`` code among the sorted ``codes`` (0 when absent)."""
    if len(codes) == 0:
        return np.zeros(len(query), dtype=np.int64)
    pos = np.clip(np.searchsorted(codes, query), 0, len(codes) - 1)
    return np.where(codes[pos] == query, counts[pos], 0)


def ruling_swaps(*args: Any, **kwargs: Any) -> SwapResult:
    """Greedy ruling-aware swaps on a CCW triangulation, then the squash flips, in one go: :func:`ruling_swaps_steps`
    (same arguments) run to its end."""
    return run_to_end(ruling_swaps_steps(*args, **kwargs))


def ruling_swaps_steps(
    vertices: np.ndarray,
    triangles: np.ndarray,
    triangle_face: np.ndarray,
    segments: np.ndarray,
    segment_is_curve: np.ndarray,
    *,
    max_valence: int = 3,
    max_swaps: int | None = None,
    squash_strain: float | None = None,
) -> Generator[str, None, SwapResult]:
    """Greedy ruling-aware swaps on a CCW triangulation, then the squash flips, in units of work (yields each unit's
    name; returns the :class:`SwapResult`); pattern ``segments`` (vertex pairs) are never swapped.

    ``max_valence``: a new endpoint may have at most this many facet edges in the face before the swap (paper: 3).
    ``max_swaps`` caps the ruling loop (default: no practical cap; the loop terminates on its own).
    ``squash_strain``: the threshold of :func:`.squash.squash_flips` (default :data:`.squash.SQUASH_STRAIN`, read
    at the call; 0 turns them off). The swaps are decided on arrays (see the module docstring) and all applied with
    ``bmesh.ops.rotate_edges``. The units: the candidates scored, the swap loop in units of :data:`SWAP_UNIT_POPS`
    queue entries, the squash flips, the ``bmesh`` built and the rotations in units of about
    :data:`SWAP_UNIT_LEVELS` swaps. A Blender job runs one unit per slice; :func:`ruling_swaps` runs them all."""
    vertices = np.asarray(vertices, dtype=float)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    triangle_face = np.asarray(triangle_face, dtype=np.int64)
    segments = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    curve = np.asarray(segment_is_curve, dtype=bool)
    if curve.any():
        scorer = EndpointScorer(vertices, segments, curve)
        swaps, decided, stats = yield from _decide_swaps_steps(
            vertices, triangles, triangle_face, segments, scorer, max_valence, max_swaps
        )
    else:  # without curve segments no endpoint scores, every cost is ∞ and no swap can lower it
        swaps, decided, stats = [], triangles.tolist(), {"convex": 0, "valence": 0, "sliver": 0}
    constrained = set(_segment_codes(segments, len(vertices)).tolist())
    threshold = SQUASH_STRAIN if squash_strain is None else squash_strain
    flips = squash_flips(vertices, decided, triangle_face.tolist(), constrained, threshold) if threshold > 0 else []
    swaps += flips
    counts = (stats["convex"], stats["valence"], stats["sliver"], len(flips))
    if not swaps:
        return SwapResult(triangles.copy(), triangle_face.copy(), 0, *counts)
    yield "squash flips"
    bm_tris = yield from _apply_with_bmesh_steps(vertices, triangles, swaps)
    tris = np.asarray(decided, dtype=np.int64).reshape(-1, 3)
    if not np.array_equal(_canonical(bm_tris), _canonical(tris)):  # pragma: no cover
        raise RuntimeError("ruling swaps: the BMesh after rotation differs from the decided triangulation")
    return SwapResult(tris, triangle_face.copy(), len(swaps), *counts)


def _apply_with_bmesh_steps(
    vertices: np.ndarray, triangles: np.ndarray, swaps: list[tuple[int, ...]]
) -> Generator[str, None, np.ndarray]:
    """Apply the decided swaps to a ``bmesh`` of the input triangles with ``bmesh.ops.rotate_edges`` (one call per
    level of independent swaps) and return the BMesh's triangles, for the check against the decided ones; yields
    after building the ``bmesh`` and after every :data:`SWAP_UNIT_LEVELS` swaps or so (whole levels). Closing the
    generator between units frees the ``bmesh``."""
    load_bpy()  # bmesh needs bpy imported first in the bpy module
    import bmesh

    bm = bmesh.new()
    try:
        verts = [bm.verts.new((float(x), float(y), 0.0)) for x, y in vertices.tolist()]
        bm.verts.index_update()
        for tri in triangles.tolist():
            bm.faces.new([verts[i] for i in tri])
        yield "bmesh built"
        rotated = 0
        for batch in _independent_runs(swaps):  # levels of disjoint rotations, in dependency order
            if rotated >= SWAP_UNIT_LEVELS:
                yield "swaps applied"
                rotated = 0
            rotated += len(batch)
            edges = []
            for a, c, *_ in batch:
                e = bm.edges.get((verts[a], verts[c]))
                if e is None:  # pragma: no cover - the half-edge structure and the BMesh went apart
                    raise RuntimeError(f"ruling swaps: edge ({a}, {c}) is missing from the BMesh")
                edges.append(e)
            out = bmesh.ops.rotate_edges(bm, edges=edges, use_ccw=False)["edges"]
            if len(out) < len(batch):
                # with several edges rotate_edges also refuses rotations it deems degenerate (in float32); a
                # single-edge rotation does not. The quads are disjoint, so the refused ones follow one by one, with
                # bmesh's per-edge rotation: a rotate_edges call per edge sets up tool flags over the whole mesh and
                # made fine curves quadratic (7,228 of 7,710 swaps refused in batch: 2.5 s; 57,000 swaps: minutes).
                # The convexity of every quad was checked when the swap was decided.
                done = {frozenset((ne.verts[0].index, ne.verts[1].index)) for ne in out}
                for (_a, _c, b, d, *_), e in zip(batch, edges, strict=True):
                    if frozenset((b, d)) not in done:
                        ne = bmesh.utils.edge_rotate(e, False)
                        if ne is not None:
                            out.append(ne)
            if len(out) != len(batch):  # pragma: no cover - every decided swap is a valid rotation
                raise RuntimeError(f"ruling swaps: bmesh rotated {len(out)} of {len(batch)} edges")
        bm_tris = np.array([[v.index for v in face.verts] for face in bm.faces], dtype=np.int64).reshape(-1, 3)
    finally:
        bm.free()
    return bm_tris


def _independent_runs(swaps: list[tuple[int, ...]]) -> list[list[tuple[int, ...]]]:
    """Group the swap sequence into levels of swaps whose quads share no triangle, respecting the order of swaps
    that do: a swap's level is one more than the highest level of the earlier swaps that touched one of its two
    triangles. Swaps in one level are disjoint rotations, which commute, so applying the levels in order gives the
    same triangulation as applying the swaps one by one, while ``rotate_edges`` pays its per-call set-up (tool-flag
    layers over the whole mesh) once per level instead of once per swap.
    """
    level_of_slot: dict[int, int] = {}
    levels: list[list[tuple[int, ...]]] = []
    for sw in swaps:
        t1, t2 = sw[4], sw[5]
        lv = max(level_of_slot.get(t1, -1), level_of_slot.get(t2, -1)) + 1
        level_of_slot[t1] = level_of_slot[t2] = lv
        if lv == len(levels):
            levels.append([])
        levels[lv].append(sw)
    return levels


def _canonical(tris: np.ndarray) -> np.ndarray:
    """Triangles rotated to start at their smallest index, rows sorted (winding kept): for set comparison."""
    k = np.argmin(tris, axis=1)
    rot = np.take_along_axis(tris, (k[:, None] + np.arange(3)[None, :]) % 3, axis=1)
    return rot[np.lexsort((rot[:, 2], rot[:, 1], rot[:, 0]))]
