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
  swap (paper condition 2, counted per face as the authors intended), the new edge does not exist yet, and the
  new cost is strictly lower;
* the candidate with the smallest new cost is swapped, repeatedly, until none is left.

Because every swap strictly lowers the total cost (∞ counted first), the loop terminates. The loop is a priority
queue with lazy re-evaluation: after a swap only the edges of the triangles around its four vertices are
re-scored (the valence and the quads change only there).

The endpoint angles depend only on which *wedge* between consecutive pattern segments at P the edge lies in, which
no swap changes (pattern segments are never swapped). So the walk around P inside the face is replaced by a lookup
among P's pattern segments sorted by angle: the same X1, X2 as the walk, in O(log deg).
"""

from __future__ import annotations

import bisect
import heapq
import math
from dataclasses import dataclass

import numpy as np

_INF = math.inf


@dataclass
class SwapResult:
    """Triangles after the swaps (CCW), their crease-pattern face, and what the loop did."""

    triangles: np.ndarray
    triangle_face: np.ndarray
    swaps: int
    convexity_checks: int
    rejected_valence: int


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
        ang = np.arctan2(d[:, 1], d[:, 0])
        order = np.lexsort((ang, ends[:, 0]))
        ends, flags, ang = ends[order], flags[order], ang[order]
        start = np.searchsorted(ends[:, 0], np.arange(n + 1))
        self._angles = [ang[start[v] : start[v + 1]].tolist() for v in range(n)]
        self._flags = [flags[start[v] : start[v + 1]].tolist() for v in range(n)]
        self._xy = self.vertices.tolist()
        self._cost: dict[tuple[int, int], float] = {}

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


def _orient(p: list[float], q: list[float], r: list[float]) -> float:
    return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])


def ruling_swaps(
    vertices: np.ndarray,
    triangles: np.ndarray,
    triangle_face: np.ndarray,
    segments: np.ndarray,
    segment_is_curve: np.ndarray,
    *,
    max_valence: int = 3,
    max_swaps: int | None = None,
) -> SwapResult:
    """Greedy ruling-aware swaps on a CCW triangulation; pattern ``segments`` (vertex pairs) are never swapped.

    ``max_valence``: a new endpoint may have at most this many facet edges in the face before the swap (paper: 3).
    ``max_swaps`` caps the loop (default: no practical cap; the loop terminates on its own).
    """
    # isort: off
    import bpy  # noqa: F401  (bmesh needs bpy imported first in the bpy module)
    import bmesh

    # isort: on

    vertices = np.asarray(vertices, dtype=float)
    triangles = np.asarray(triangles, dtype=np.int64)
    triangle_face = np.asarray(triangle_face, dtype=np.int64)
    segments = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    scorer = EndpointScorer(vertices, segments, np.asarray(segment_is_curve, dtype=bool))
    constrained = {(int(min(a, b)), int(max(a, b))) for a, b in segments.tolist()}
    scale2 = float(np.sum((vertices.max(0) - vertices.min(0)) ** 2)) or 1.0
    eps = 1e-12 * scale2
    xy = vertices.tolist()

    bm = bmesh.new()
    try:
        face_layer = bm.faces.layers.int.new("cp_face")
        verts = [bm.verts.new((float(x), float(y), 0.0)) for x, y in vertices.tolist()]
        bm.verts.index_update()
        for tri, f in zip(triangles.tolist(), triangle_face.tolist(), strict=True):
            face = bm.faces.new([verts[i] for i in tri])
            face[face_layer] = f
        bm.edges.ensure_lookup_table()

        # facet valence per (vertex, crease-pattern face)
        valence: dict[tuple[int, int], int] = {}
        for e in bm.edges:
            a, b = e.verts[0].index, e.verts[1].index
            if (min(a, b), max(a, b)) in constrained or len(e.link_faces) != 2:
                continue
            f = e.link_faces[0][face_layer]
            valence[(a, f)] = valence.get((a, f), 0) + 1
            valence[(b, f)] = valence.get((b, f), 0) + 1

        stats = {"convex": 0, "valence": 0}

        def evaluate(e) -> tuple[float, tuple[int, int]] | None:
            """The new cost if e is a swap candidate, with the new edge's key; None otherwise."""
            if not e.is_valid or len(e.link_faces) != 2:
                return None
            a, c = e.verts[0].index, e.verts[1].index
            if (min(a, c), max(a, c)) in constrained:
                return None
            f1, f2 = e.link_faces
            b = next(v.index for v in f1.verts if v.index != a and v.index != c)
            d = next(v.index for v in f2.verts if v.index != a and v.index != c)
            key = (min(b, d), max(b, d))
            if key in constrained:
                return None
            new = scorer.cost(b, d)
            if not new < scorer.cost(a, c):
                return None
            stats["convex"] += 1
            pa, pb, pc, pd = xy[a], xy[b], xy[c], xy[d]
            o1, o2 = _orient(pb, pd, pa), _orient(pb, pd, pc)
            o3, o4 = _orient(pa, pc, pb), _orient(pa, pc, pd)
            if not ((o1 > eps and o2 < -eps) or (o1 < -eps and o2 > eps)):
                return None
            if not ((o3 > eps and o4 < -eps) or (o3 < -eps and o4 > eps)):
                return None
            f = f1[face_layer]
            if valence.get((b, f), 0) > max_valence or valence.get((d, f), 0) > max_valence:
                stats["valence"] += 1
                return None
            if bm.edges.get((verts[b], verts[d])) is not None:
                return None
            return new, key

        heap: list[tuple[float, tuple[int, int], tuple[int, int], int, object]] = []
        counter = [0]

        def push(e) -> None:
            r = evaluate(e)
            if r is not None:
                a, c = e.verts[0].index, e.verts[1].index
                counter[0] += 1
                heapq.heappush(heap, (r[0], r[1], (min(a, c), max(a, c)), counter[0], e))

        for e in bm.edges:
            push(e)
        swaps = 0
        cap = max_swaps if max_swaps is not None else 100 * max(1, len(bm.edges))
        while heap and swaps < cap:
            cost, key, _old, _n, e = heapq.heappop(heap)
            r = evaluate(e)
            if r is None:
                continue
            if r[0] != cost:  # stale entry: its value changed since it was queued
                push(e)
                continue
            a, c = e.verts[0].index, e.verts[1].index
            f = e.link_faces[0][face_layer]
            out = bmesh.ops.rotate_edges(bm, edges=[e], use_ccw=False)["edges"]
            if not out:  # pragma: no cover - evaluate() already excludes what rotate_edges refuses
                continue
            ne = out[0]
            nb, nd = ne.verts[0].index, ne.verts[1].index
            if (min(nb, nd), max(nb, nd)) != key:  # pragma: no cover - rotation must connect the opposite corners
                raise RuntimeError(f"edge rotation produced ({nb}, {nd}) instead of {key}")
            for face in ne.link_faces:  # bmesh does not carry face layers through rotation
                face[face_layer] = f
            swaps += 1
            valence[(a, f)] -= 1
            valence[(c, f)] -= 1
            valence[(nb, f)] = valence.get((nb, f), 0) + 1
            valence[(nd, f)] = valence.get((nd, f), 0) + 1
            seen = set()
            for vi in (a, c, nb, nd):
                for face in verts[vi].link_faces:
                    for edge in face.edges:
                        if edge not in seen:
                            seen.add(edge)
                            push(edge)

        tris = np.array([[v.index for v in face.verts] for face in bm.faces], dtype=np.int64).reshape(-1, 3)
        tface = np.array([face[face_layer] for face in bm.faces], dtype=np.int64)
    finally:
        bm.free()
    return SwapResult(tris, tface, swaps, stats["convex"], stats["valence"])
