"""Polylines of a crease pattern: chains of segments through vertices where exactly two meet.

A FOLD file (or a discretised pattern) holds straight segments only; chaining them gives back the polylines a
designer drew — one editable curve per chain of one assignment and angle instead of hundreds of segments — for the
Import operator, the crease-curve display of a folded mesh and the SVG export — and tells which chains are curves
drawn as polylines (:func:`flattened_curves`), so the ruling swaps treat them as the curves they are. The distance of
points from segments (:func:`point_segment_distance`) lives here for those tests and for the discretisation.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .model import CreaseCurve, CreasePattern, CurveSegment


def connected_components(n: int, t1: np.ndarray, t2: np.ndarray) -> np.ndarray:
    """Connected components of n nodes joined by the pairs (t1, t2): each node's label is the smallest node index of
    its component (vectorised hooking of roots onto smaller labels with pointer jumping). Here, the pattern's stage,
    so the polylines' chains and the border's gaps use it as the mesh's regions and pieces do."""
    lab = np.arange(n)
    while True:
        l1, l2 = lab[t1], lab[t2]
        m = np.minimum(l1, l2)
        new = lab.copy()
        np.minimum.at(new, l1, m)
        np.minimum.at(new, l2, m)
        while True:
            jumped = new[new]
            if np.array_equal(jumped, new):
                break
            new = jumped
        if np.array_equal(new, lab):
            return lab
        lab = new


def segment_foot(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise, the point of segment ``a → b`` nearest ``p`` (``a`` for a segment of no length)."""
    ab = b - a
    ll = np.einsum("ij,ij->i", ab, ab)
    t = np.where(ll > 0, np.einsum("ij,ij->i", p - a, ab) / np.where(ll > 0, ll, 1.0), 0.0)
    return a + np.clip(t, 0.0, 1.0)[:, None] * ab


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise distance of ``p`` from the segment ``a → b`` (the discretisation's tolerance test, the border gaps,
    the flattened curves' straightness)."""
    return np.hypot(*(p - segment_foot(p, a, b)).T)


def ends_in_pairs(edges: np.ndarray, codes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pairs of edges that meet two by two: ``codes`` (one per edge end, ``edges.ravel()``'s order) says which
    ends meet (a vertex, or a vertex and a role), and where exactly two ends share a code their edges ``k1``, ``k2``
    are a pair, with ``at`` the vertex of those ends; pairs in the order of their codes. The chains of a drawing (its
    flattened curves, a FOLD file's strokes) and the verdict's stretches of crease are joined at such vertices."""
    order = np.argsort(codes, kind="stable")
    c = codes[order]
    starts = np.flatnonzero(np.r_[True, c[1:] != c[:-1]])
    pair = starts[np.diff(np.r_[starts, len(c)]) == 2]
    j1, j2 = order[pair], order[pair + 1]
    return j1 // 2, j2 // 2, np.asarray(edges).ravel()[j1]


def _turn_cosines(
    v: np.ndarray, e: np.ndarray, k1: np.ndarray, k2: np.ndarray, at: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Where edges ``k1`` and ``k2`` meet at vertex ``at``: the cosine of the turn from one to the other, and the
    product of their lengths (0 for an edge of no length, whose cosine is then 0)."""
    o1, o2 = e[k1].sum(axis=1) - at, e[k2].sum(axis=1) - at
    u, w = v[at] - v[o1], v[o2] - v[at]
    norms = np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1)
    return np.einsum("ij,ij->i", u, w) / np.where(norms > 0, norms, 1.0), norms


def _angle_key(fold_angles: np.ndarray) -> np.ndarray:
    """Fold angles as comparable keys: rounded to 1e-9°, a missing angle (``nan``) as ``inf``, so two segments of one
    drawn angle compare equal."""
    return np.round(np.nan_to_num(np.asarray(fold_angles, dtype=float), nan=np.inf), 9)


def chain_edges(edges: np.ndarray) -> list[np.ndarray]:
    """Split an edge set into chains of vertex indices: walks through vertices of degree 2, ends at branch points.

    Open chains start at their ends; what is left are closed loops (first vertex repeated at the end). Used for the
    crease-curve children, the SVG export and reading FOLD files as curves; not on any solver path.
    """
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    adjacency: dict[int, list[int]] = {}
    for k, (a, b) in enumerate(edges.tolist()):
        adjacency.setdefault(a, []).append(k)
        adjacency.setdefault(b, []).append(k)
    used = np.zeros(len(edges), dtype=bool)
    chains: list[np.ndarray] = []

    def walk(start: int, k: int | None) -> np.ndarray:
        chain = [start]
        v = start
        while k is not None and not used[k]:
            used[k] = True
            a, b = edges[k]
            v = int(b if a == v else a)
            chain.append(v)
            nxt = [j for j in adjacency[v] if not used[j]]
            k = nxt[0] if len(adjacency[v]) == 2 and nxt else None
        return np.array(chain, dtype=np.int64)

    for v, ks in adjacency.items():
        if len(ks) != 2:
            for k in ks:
                if not used[k]:
                    chains.append(walk(v, k))
    for k in range(len(edges)):
        if not used[k]:
            chains.append(walk(int(edges[k][0]), k))
    return chains


def drawn_strokes(pattern: CreasePattern) -> CreasePattern:
    """``pattern`` (straight segments, each its own polyline: another tool's FOLD file) with its segments grouped
    into the strokes a designer drew: chains through the vertices where exactly two segments of one assignment and
    fold angle meet and turn by at most :data:`MAX_CURVE_TURN_DEG` — a curve's pieces, and a straight crease's
    pieces on either side of a crossing. Each stroke is named after its file edges (``"t.fold edges 12, 13, … (9
    in one stroke)"``).

    The verdict judges a drawn crease by its length (more than half of it flat or folded the wrong way); with every
    edge a crease of its own, the same fold of the same mesh was flagged from a FOLD file and not from its SVG
    twin (a designer's curved hypar: "37 crease(s), 8 %" against one crease, 2.8 %), and named file edges, not
    creases. Chained, the FOLD file's creases are the SVG's."""
    e = np.asarray(pattern.edges, dtype=np.int64).reshape(-1, 2)
    m = len(e)
    if m < 2:
        return pattern
    v = np.asarray(pattern.vertices, dtype=float)
    _, key = np.unique(
        np.stack(
            [np.unique(pattern.assignments, return_inverse=True)[1].astype(float), _angle_key(pattern.fold_angles)]
        ),
        axis=1,
        return_inverse=True,
    )
    key = key.reshape(-1)
    k1, k2, mid = ends_in_pairs(e, e.ravel() * (int(key.max()) + 1) + np.repeat(key, 2))  # (vertex, key) per end
    cos_turn, norms = _turn_cosines(v, e, k1, k2, mid)
    joint = (k1 != k2) & (norms > 0) & (cos_turn >= math.cos(math.radians(MAX_CURVE_TURN_DEG + 1e-3)))
    label = connected_components(m, k1[joint], k2[joint])
    ids, stroke = np.unique(label, return_inverse=True)
    stroke = stroke.reshape(-1)
    if len(ids) == m:
        return pattern
    members: list[list[int]] = [[] for _ in ids]
    for k, s in enumerate(stroke.tolist()):  # file edges per stroke, in file order (a split edge named once)
        poly = int(pattern.edge_polyline[k])
        if not members[s] or members[s][-1] != poly:
            members[s].append(poly)
    names = [_stroke_name(pattern.sources, sorted(set(ks))) for ks in members]
    return replace(pattern, edge_polyline=stroke.astype(np.int64), sources=names)


def _stroke_name(sources: list[str], polys: list[int]) -> str:
    """A stroke's name from its segments' own (``"t.fold edge 12"``): the first's, or ``"t.fold edges 12, 13, …
    (9 in one stroke)"``."""
    named = [sources[k] if 0 <= k < len(sources) else f"edge {k}" for k in polys]
    if len(named) == 1:
        return named[0]
    head = named[0].rpartition(" edge ")[0]
    if not head or not all(s.startswith(head + " edge ") for s in named):
        return f"{named[0]} and {len(named) - 1} more in one stroke"
    listed = ", ".join(s.rpartition(" edge ")[2] for s in named[:2])
    return f"{head} edges {listed}" + (f", … ({len(named)} in one stroke)" if len(named) > 2 else "")


MAX_CURVE_TURN_DEG = 30.0
"""The sharpest turn between two pieces of one flattened curve (degrees): a sharper one is a corner of the drawing.

A curve sampled at the paper's interval turns a few degrees per piece (a circle of 20 pieces: 18°, of 12: 30°,
counted in whatever the round-off); a polygon's corners (a hexagon's 60°, a square's 90°) and a crease's kinks are
drawn corners."""


def flattened_curves(
    vertices: np.ndarray, edges: np.ndarray, assignments: np.ndarray, fold_angles: np.ndarray, tolerance: float
) -> np.ndarray:
    """Which segments are pieces of a curve drawn as a polyline (bool per edge).

    Paper §3.3 scores an edge by how well it bisects the *curve* at its ends, so the ruling swaps need to know which
    segments discretise a curve. A Bézier says so itself; a polyline does not: Origami Simulator's ``<line>``
    elements, a tool that flattens curves on export, a FOLD file, our own SVG export read back. Read as straight
    creases, they got the plain constrained Delaunay mesh: on the designer's curved Resch grid read back from our
    SVG export the fold's mean warp was 16.3° instead of 13.1°.

    A *chain* runs through the vertices where exactly two segments meet, both of one assignment and fold angle (not
    facet lines, ``F``), turning by at most :data:`MAX_CURVE_TURN_DEG`. A chain is a flattened curve when it closes
    on itself or when one of its vertices is farther than ``tolerance`` (the discretisation's, mm) from the straight
    line between its ends: a straight crease cut into pieces stays straight (so do the pieces of a straight border
    split at the interval), a curve sampled within that tolerance would have been a single chord."""
    v = np.asarray(vertices, dtype=float)
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    m, n = len(e), len(v)
    out = np.zeros(m, dtype=bool)
    if m == 0:
        return out
    k1, k2, mid = ends_in_pairs(e, e.ravel())  # the vertices where exactly two segments meet
    cos_turn, norms = _turn_cosines(v, e, k1, k2, mid)
    role = np.asarray(assignments)
    angle = _angle_key(fold_angles)
    joint = (
        (role[k1] == role[k2])
        & (role[k1] != "F")
        & (angle[k1] == angle[k2])
        & (norms > 0)
        & (cos_turn >= math.cos(math.radians(MAX_CURVE_TURN_DEG + 1e-3)))  # a 12-gon's 30° in, whatever the digits
    )
    mid, k1, k2 = mid[joint], k1[joint], k2[joint]
    if len(mid) == 0:
        return out
    chained = np.unique(np.concatenate([k1, k2]))
    label = connected_components(m, k1, k2)[chained]  # the segments joined at a chain's vertices
    is_joint = np.zeros(n, dtype=bool)
    is_joint[mid] = True
    for chain in np.split(chained[np.argsort(label, kind="stable")], np.flatnonzero(np.diff(np.sort(label))) + 1):
        nodes = np.unique(e[chain])
        tips = nodes[~is_joint[nodes]]
        if len(tips) == 0:  # a closed loop
            out[chain] = True
            continue
        a, b = np.broadcast_to(v[tips[0]], v[nodes].shape), np.broadcast_to(v[tips[-1]], v[nodes].shape)
        out[chain] = float(np.max(point_segment_distance(v[nodes], a, b))) > tolerance
    return out


OVERSAMPLED_FRACTION = 0.5
"""A drawn polyline whose median piece is shorter than this fraction of the interval is thinned
(:func:`thin_dense_polylines`): the paper's own sampling (chords up to the interval, refined where a chord strays
beyond the tolerance) has its median piece at half the interval or more, except on curves tighter than the tolerance
allows, which thinning leaves as they are. It was a quarter until the fifteenth pass: a designer's 300-point sine
(1.34 mm pieces on a 400 mm sheet) was thinned at an 8 mm interval and kept point for point at 5 mm, which fanned
482 corners under 1° onto it; at a half it is thinned at 5 mm too (516 faces, none under 1°). Of 359 drawings, the
fixtures and the examples, one changes (a shell of flattened arcs with drawn rungs: 1,162 → 602 faces, its figures
alike)."""


def thin_dense_polylines(
    vertices: np.ndarray,
    edges: np.ndarray,
    assignments: np.ndarray,
    fold_angles: np.ndarray,
    drawn: np.ndarray,
    interval: float,
    tolerance: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Thin the oversampled polylines among the ``edges`` marked in ``drawn`` (drawn as polylines, curved or
    straight) to the paper's sampling: returns ``(kept, chords, source)``: a bool per edge (False for the pieces
    replaced), the new chords ``(k, 2)`` and for each the edge whose attributes it takes.

    A curve (or a straight line) drawn as a polyline far finer than the interval (a CAD program's 1 mm polyline of a
    1 m sheet: 52,326 faces and 245 s where its Béziers give 2,348 faces and 2.8 s; 0.05 mm pieces rounded to two
    decimals, which fold as a zigzag) is walked from each vertex that must stay — a junction, an end, a change of
    assignment or angle — and each chord is taken as long as it stays within ``interval`` and keeps every skipped
    vertex within ``tolerance`` of it (paper §3.1), and no other vertex of the pattern lies within ``tolerance`` of
    it. The kept vertices are drawn ones: nothing moves. Only chains whose median piece is under
    :data:`OVERSAMPLED_FRACTION` of the interval are thinned, so a pattern sampled as the paper samples (our own SVG
    export) reads back unchanged.
    """
    v = np.asarray(vertices, dtype=float)
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    m, n = len(e), len(v)
    kept = np.ones(m, dtype=bool)
    none = (kept, np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=np.int64))
    if m == 0 or not np.any(drawn) or not (interval > 0 and tolerance > 0):
        return none
    deg = np.bincount(e.ravel(), minlength=n)
    angle = _angle_key(fold_angles)
    role = np.asarray(assignments)
    index = {(int(a), int(b)): k for k, (a, b) in enumerate(e.tolist())}
    index.update({(b, a): k for (a, b), k in list(index.items())})
    cell = max(interval, tolerance)
    grid: dict[tuple[int, int], list[int]] = {}
    for i, (x, y) in enumerate(v.tolist()):
        grid.setdefault((int(x // cell), int(y // cell)), []).append(i)

    def clear(chain: np.ndarray, i: int, j: int) -> bool:
        """No vertex within ``tolerance`` of the chord from ``chain[i]`` to ``chain[j]`` but those it replaces and
        those its chain goes on through beside its ends (:func:`_beside`)."""
        a, b, inside = int(chain[i]), int(chain[j]), _beside(v, chain, i, j, tolerance)
        lo, hi = np.minimum(v[a], v[b]) - tolerance, np.maximum(v[a], v[b]) + tolerance
        near = [
            k
            for cx in range(int(lo[0] // cell), int(hi[0] // cell) + 1)
            for cy in range(int(lo[1] // cell), int(hi[1] // cell) + 1)
            for k in grid.get((cx, cy), ())
            if k not in inside
        ]
        if not near:
            return True
        pts = v[near]
        d = point_segment_distance(pts, np.broadcast_to(v[a], pts.shape), np.broadcast_to(v[b], pts.shape))
        return bool(np.all(d > tolerance))

    chords: list[tuple[int, int]] = []
    source: list[int] = []
    for chain in chain_edges(e[drawn]):
        pieces = np.array([index[(int(a), int(b))] for a, b in zip(chain[:-1], chain[1:], strict=True)])
        lengths = np.hypot(*(v[chain[1:]] - v[chain[:-1]]).T)
        if np.median(lengths) >= OVERSAMPLED_FRACTION * interval:
            continue
        # vertices that stay: the chain's ends, junctions, a change of assignment or fold angle
        fixed = np.zeros(len(chain), dtype=bool)
        fixed[[0, -1]] = True
        inner = np.arange(1, len(chain) - 1)
        fixed[inner] = (
            (deg[chain[inner]] != 2)
            | (role[pieces[inner - 1]] != role[pieces[inner]])
            | (angle[pieces[inner - 1]] != angle[pieces[inner]])
        )
        if chain[0] == chain[-1] and len(chain) > 3:
            # a closed loop keeps three vertices at least: thinned from its one stop it could shrink to two chords
            # between the same two vertices, or one back to its start (a 0.1 mm slot drawn as a closed cut)
            fixed[[len(chain) // 3, 2 * len(chain) // 3]] = True
        stops = np.flatnonzero(fixed)
        for s0, s1 in zip(stops[:-1], stops[1:], strict=True):
            i = int(s0)
            while i < s1:
                best = i + _reach(v[chain[i : int(s1) + 1]], interval, tolerance)
                # the vertices a chord replaces are no obstacle, nor those its chain goes on through within the
                # tolerance of its ends (a polyline drawn finer than the tolerance: the next one always is, and
                # nothing was thinned: 0.05 mm points gave 17,976 faces and 40 s); the rest of its chain is (the
                # far side of a slot)
                if best > i + 1 and not clear(chain, i, best):
                    # the longest clear chord below it, by bisection (a chord clear of other vertices is so when
                    # shortened): one step at a time, a 150,000-point circle took 90,000 tests and 40 s
                    lo, hi = i + 1, best
                    while hi - lo > 1:
                        mid = (lo + hi) // 2
                        lo, hi = (mid, hi) if clear(chain, i, mid) else (lo, mid)
                    best = lo
                if best > i + 1:
                    kept[pieces[i:best]] = False
                    chords.append((int(chain[i]), int(chain[best])))
                    source.append(int(pieces[i]))
                i = best
    if not chords:
        return none
    return kept, np.array(chords, dtype=np.int64), np.array(source, dtype=np.int64)


def _beside(v: np.ndarray, chain: np.ndarray, i: int, j: int, tolerance: float) -> set[int]:
    """The vertices of ``chain`` from ``i`` to ``j`` and those its chain goes on through, before ``i`` and after
    ``j``, while they stay within ``tolerance`` of that end and beyond it (their nearest point of the chord ``i``–``j``
    is that end: one that comes back alongside the chord is an obstacle)."""
    a, b = v[chain[i]], v[chain[j]]
    d = b - a
    dd = float(d @ d) or 1.0
    lo, hi = i, j
    while lo > 0 and np.hypot(*(v[chain[lo - 1]] - a)) <= tolerance and (v[chain[lo - 1]] - a) @ d <= 0.0:
        lo -= 1
    while hi < len(chain) - 1 and np.hypot(*(v[chain[hi + 1]] - b)) <= tolerance and (v[chain[hi + 1]] - a) @ d >= dd:
        hi += 1
    return set(chain[lo : hi + 1].tolist())


MAX_REACH = 2048
"""Most pieces one chord may replace when thinning a polyline (:func:`_reach`): bounds its count × count arrays."""


def _reach(points: np.ndarray, interval: float, tolerance: float) -> int:
    """How many pieces of the polyline ``points`` (from its first point) one chord can replace: the largest ``j``
    whose chord ``points[0]``–``points[j]``, and every shorter one, is within ``interval`` and keeps the points it
    skips within ``tolerance`` (at least 1). All candidate chords at once: one array of their distances."""
    a = points[0]
    reach = np.hypot(*(points[1:] - a).T) <= interval
    reach[0] = True
    count = int(np.argmin(reach)) if not reach.all() else len(reach)  # chords 1..count are short enough
    # and no longer along the polyline than twice the interval (what a chord within the tolerance of it can
    # replace): a tight spiral keeps thousands of points within the interval of its start, and the arrays below
    # are count × count (a review session's 20,000-point spiral took 12 GB)
    along = np.cumsum(np.hypot(*np.diff(points[: count + 1], axis=0).T))
    count = min(count, max(1, int(np.searchsorted(along, 2.0 * interval, side="right"))), MAX_REACH)
    if count < 2:
        return 1
    ends, inner = points[1 : count + 1], points[1:count]  # chord ends j = 1..count, the points they may skip
    ab = ends - a
    ll = np.einsum("ij,ij->i", ab, ab)  # 0 for a chord back to the start of a closed loop
    t = np.clip((inner - a) @ ab.T / np.where(ll > 0, ll, 1.0), 0.0, 1.0)  # (inner, chords)
    gap = np.hypot(inner[:, None, 0] - (a[0] + t * ab[None, :, 0]), inner[:, None, 1] - (a[1] + t * ab[None, :, 1]))
    skipped = np.arange(count - 1)[:, None] < np.arange(count)[None, :]  # chord j skips points 1..j-1
    ok = np.where(skipped, gap, 0.0).max(axis=0) <= tolerance
    return int(np.argmin(ok)) if not ok.all() else count


def curves_from_pattern(pattern: CreasePattern) -> list[CreaseCurve]:
    """Chain the straight segments of a discretised pattern into polyline :class:`CreaseCurve` s.

    Segments are grouped by (assignment, fold angle, source polyline) and chained through vertices of degree 2
    within the group, so a FOLD file's discretised curve comes back as one editable curve, not hundreds. A plain
    FOLD file (every edge its own polyline) is grouped by assignment and angle only.
    """
    angles = _angle_key(pattern.fold_angles)
    poly_ids = pattern.edge_polyline
    if len(np.unique(poly_ids)) == len(poly_ids):  # plain FOLD: one "polyline" per edge carries no grouping
        poly_ids = np.full(len(poly_ids), -1)
    keys = {}
    rows = zip(pattern.assignments.tolist(), angles.tolist(), poly_ids.tolist(), strict=True)
    for i, key in enumerate(rows):
        keys.setdefault(key, []).append(i)
    curves: list[CreaseCurve] = []
    for (assignment, angle, poly), idx in keys.items():
        for chain in chain_edges(pattern.edges[idx]):
            pts = pattern.vertices[chain]
            closed = len(chain) > 2 and chain[0] == chain[-1]
            segs = [CurveSegment("line", np.array([pts[k], pts[k + 1]])) for k in range(len(pts) - 1)]
            src = pattern.sources[poly] if 0 <= poly < len(pattern.sources) else f"FOLD edges {idx[:3]}..."
            curves.append(
                CreaseCurve(
                    segments=segs,
                    assignment=assignment,
                    fold_angle=None if not np.isfinite(angle) else float(angle),
                    closed=bool(closed),
                    source=src,
                )
            )
    return curves
