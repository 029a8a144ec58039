"""Constrained Delaunay triangulation of a crease pattern, without interior (Steiner) points (paper §3.2).

Every crease and border segment becomes a triangle edge; the only vertices are the pattern's own. The paper uses
CDT instead of ear clipping because Delaunay triangles are "fatter": fewer long fans meeting at one vertex, which
would act as cone rulings.

Pipeline (:func:`constrained_triangulation`):

1. CDT of the convex hull of all pattern vertices with every segment as a constraint, by one of two backends behind
   one function: ``triangle`` (Shewchuk's Triangle from PyPI, switch ``pc``: no quality switches, so no Steiner
   points) or ``mathutils`` (``mathutils.geometry.delaunay_2d_cdt``, always available in Blender). Any added or
   merged vertex means the segments cross or vertices coincide: a :class:`~.pattern.PatternError` names them.
2. Canonicalisation, identical for both backends: a Lawson pass in double precision flips every non-constraint edge
   that is not locally Delaunay, and cocircular ties (up to a relative tolerance) are broken deterministically
   (the diagonal that touches the quad's smallest vertex index wins). Triangles are then sorted. So both backends
   give the *same* arrays on the same input, even on regular grids or concentric circles.
3. Regions: triangles connected across non-constraint edges form the crease-pattern faces. The region touching the
   convex hull through a non-constraint edge is outside; crossing a border (``B``) segment toggles inside/outside,
   crossing any other segment keeps it. Outside regions and holes are dropped.

Cuts are split afterwards (:func:`split_cuts`, Origami Simulator's ``splitCuts``): each cut becomes two border edges
and each vertex is duplicated once per extra fan of triangles separated by cuts.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from curved_fold.core.pattern import CreasePattern, PatternError

BACKENDS = ("auto", "triangle", "mathutils")

_TIE_TOLERANCE = 1e-10
"""Relative in-circle determinant (normalised by the quad's size⁴) under which four points count as cocircular."""


@dataclass
class PlanarTriangulation:
    """A CDT of the sheet, before cut splitting.

    * ``vertices`` ``(n, 2)``: the pattern vertices that lie on some segment (isolated ones are dropped);
      ``vertex_source`` ``(n,)`` maps them to pattern vertex indices.
    * ``triangles`` ``(t, 3)`` CCW, sorted canonically; ``triangle_region`` ``(t,)`` index into ``faces``.
    * ``faces``: one CCW outer boundary loop per crease-pattern face (vertex indices); ``face_loops`` all loops of
      each face (outer first; inner loops around islands are clockwise); ``face_simple`` whether a face is a simple
      polygon (one loop, no repeated vertex).
    * ``segment_of``: ``{(i, j) with i < j: pattern edge index}`` for triangle sides that are pattern segments.
    """

    vertices: np.ndarray
    vertex_source: np.ndarray
    triangles: np.ndarray
    triangle_region: np.ndarray
    faces: list[np.ndarray]
    face_loops: list[list[np.ndarray]]
    face_simple: np.ndarray
    segment_of: dict[tuple[int, int], int]
    backend: str
    warnings: list[str] = field(default_factory=list)


# ----------------------------------------------------------------------------------------------------------------
# geometry predicates
# ----------------------------------------------------------------------------------------------------------------


def orient(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Twice the signed area of (a, b, c), vectorised over leading axes (> 0: counter-clockwise)."""
    return (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])


def incircle(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """In-circle determinant of d against CCW (a, b, c), normalised by the size⁴ of the four points.

    > 0: d lies strictly inside the circumcircle (the edge opposite d's triangle is not locally Delaunay).
    """
    pts = np.stack([a, b, c, d])
    centre = pts.mean(axis=0)
    scale = np.max(np.abs(pts - centre), axis=(0, -1)) + 1e-300
    ad, bd, cd = ((p - d) / scale[..., None] for p in (a, b, c))
    adl = ad[..., 0] ** 2 + ad[..., 1] ** 2
    bdl = bd[..., 0] ** 2 + bd[..., 1] ** 2
    cdl = cd[..., 0] ** 2 + cd[..., 1] ** 2
    return (
        adl * (bd[..., 0] * cd[..., 1] - bd[..., 1] * cd[..., 0])
        - bdl * (ad[..., 0] * cd[..., 1] - ad[..., 1] * cd[..., 0])
        + cdl * (ad[..., 0] * bd[..., 1] - ad[..., 1] * bd[..., 0])
    )


# ----------------------------------------------------------------------------------------------------------------
# backends
# ----------------------------------------------------------------------------------------------------------------


def _have_triangle() -> bool:
    try:
        import triangle  # noqa: F401
    except ImportError:
        return False
    return True


def resolve_backend(backend: str) -> str:
    """``"auto"`` → ``"triangle"`` when the ``triangle`` package imports, else ``"mathutils"``."""
    if backend not in BACKENDS:
        raise ValueError(f"unknown triangulation backend {backend!r}; expected one of {BACKENDS}")
    if backend == "auto":
        return "triangle" if _have_triangle() else "mathutils"
    return backend


def _cdt_triangle(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    import triangle

    out = triangle.triangulate({"vertices": points, "segments": segments}, "pcQ")
    if len(out["vertices"]) != len(points):
        extra = out["vertices"][len(points)]
        raise PatternError(
            f"triangulation: segments cross or touch near ({extra[0]:.4g}, {extra[1]:.4g}) mm; the pattern must be "
            "discretised with intersections split (Triangle added a vertex there)"
        )
    return np.asarray(out["triangles"], dtype=np.int64)


def _cdt_mathutils(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    import bpy  # noqa: F401  (mathutils needs bpy imported first in the bpy module)
    from mathutils.geometry import delaunay_2d_cdt

    centre = points.mean(axis=0)
    scale = float(np.max(np.abs(points - centre))) or 1.0
    coords = [tuple(p) for p in ((points - centre) / scale).tolist()]
    verts, _edges, faces, orig_verts, _oe, _of = delaunay_2d_cdt(coords, segments.tolist(), [], 0, 1e-9, True)
    remap = np.full(len(verts), -1, dtype=np.int64)
    for k, orig in enumerate(orig_verts):
        if len(orig) == 0:
            p = np.asarray(verts[k][:2]) * scale + centre
            raise PatternError(
                f"triangulation: segments cross near ({p[0]:.4g}, {p[1]:.4g}) mm; the pattern must be discretised "
                "with intersections split (delaunay_2d_cdt added a vertex there)"
            )
        if len(orig) > 1:
            p = points[orig[0]]
            raise PatternError(
                f"triangulation: pattern vertices {sorted(orig)} coincide at ({p[0]:.4g}, {p[1]:.4g}) mm; merge them "
                "first (merge tolerance)"
            )
        remap[k] = orig[0]
    tris = []
    for f in faces:
        if len(f) != 3:  # output type 0 gives triangles only; be defensive
            f = list(f)
            tris += [(f[0], f[i], f[i + 1]) for i in range(1, len(f) - 1)]
        else:
            tris.append(tuple(f))
    return remap[np.asarray(tris, dtype=np.int64).reshape(-1, 3)]


# ----------------------------------------------------------------------------------------------------------------
# canonical Delaunay (same result from both backends)
# ----------------------------------------------------------------------------------------------------------------


def _canonical_triangles(tris: np.ndarray) -> np.ndarray:
    """Rotate each triangle so its smallest index comes first (keeps the winding), then sort the rows."""
    k = np.argmin(tris, axis=1)
    idx = (k[:, None] + np.arange(3)[None, :]) % 3
    rot = np.take_along_axis(tris, idx, axis=1)
    order = np.lexsort((rot[:, 2], rot[:, 1], rot[:, 0]))
    return rot[order]


def legalise(points: np.ndarray, tris: np.ndarray, constrained: set[tuple[int, int]]) -> tuple[np.ndarray, int]:
    """Lawson flips until every non-constraint edge is locally Delaunay, with deterministic cocircular tie-breaks.

    A quad whose in-circle value is within :data:`_TIE_TOLERANCE` of zero is a tie: its diagonal must touch the
    smallest vertex index of the quad. Returns the new triangles and the number of flips. Vectorised check first;
    the Python flip loop only runs over the (usually few) offending edges and their neighbours.
    """
    tris = [list(t) for t in tris.tolist()]
    owner: dict[tuple[int, int], int] = {}
    for ti, (a, b, c) in enumerate(tris):
        owner[(a, b)] = ti
        owner[(b, c)] = ti
        owner[(c, a)] = ti

    def third(ti: int, a: int, b: int) -> int:
        t = tris[ti]
        for v in t:
            if v != a and v != b:
                return v
        raise AssertionError("degenerate triangle")

    def wants_flip(a: int, b: int) -> bool:
        """Edge a→b (t1 on its left) should become the other diagonal."""
        if (min(a, b), max(a, b)) in constrained:
            return False
        t1, t2 = owner.get((a, b), -1), owner.get((b, a), -1)
        if t1 < 0 or t2 < 0:
            return False
        c, d = third(t1, a, b), third(t2, b, a)
        pa, pb, pc, pd = points[a], points[b], points[c], points[d]
        # the quad a, d, b, c must be strictly convex: both new triangles (c, a, d), (d, b, c) counter-clockwise
        if orient(pc, pa, pd) <= 0 or orient(pd, pb, pc) <= 0:
            return False
        val = float(incircle(pa, pb, pc, pd))
        if val > _TIE_TOLERANCE:
            return True
        if val < -_TIE_TOLERANCE:
            return False
        return min(c, d) < min(a, b)

    # vectorised screening of every interior edge (each undirected edge once)
    arr = np.asarray(tris, dtype=np.int64)
    a_, b_ = arr.reshape(-1), np.roll(arr, -1, axis=1).reshape(-1)
    cand = [(int(a), int(b)) for a, b in zip(a_, b_, strict=True) if a < b and (b, a) in owner]
    if cand:
        ca = np.array(cand)
        c = np.array([third(owner[(a, b)], a, b) for a, b in cand])
        d = np.array([third(owner[(b, a)], b, a) for a, b in cand])
        val = incircle(points[ca[:, 0]], points[ca[:, 1]], points[c], points[d])
        stack = [cand[i] for i in np.flatnonzero(val >= -_TIE_TOLERANCE)]
    else:
        stack = []
    flips = 0
    limit = 50 * len(tris) + 100
    while stack:
        a, b = stack.pop()
        if (a, b) not in owner:
            a, b = b, a
            if (a, b) not in owner:
                continue
        if not wants_flip(a, b):
            continue
        flips += 1
        if flips > limit:  # pragma: no cover - Lawson flips terminate; guard against tolerance cycles
            raise RuntimeError("triangulation: Delaunay legalisation did not terminate")
        t1, t2 = owner[(a, b)], owner[(b, a)]
        c, d = third(t1, a, b), third(t2, b, a)
        for e in ((a, b), (b, c), (c, a), (b, a), (a, d), (d, b)):
            owner.pop(e, None)
        tris[t1] = [c, a, d]
        tris[t2] = [d, b, c]
        for ti in (t1, t2):
            x, y, z = tris[ti]
            owner[(x, y)] = ti
            owner[(y, z)] = ti
            owner[(z, x)] = ti
        stack += [(a, d), (d, b), (b, c), (c, a)]
    return np.asarray(tris, dtype=np.int64).reshape(-1, 3), flips


# ----------------------------------------------------------------------------------------------------------------
# regions (crease-pattern faces)
# ----------------------------------------------------------------------------------------------------------------


def _find(parent: list[int], i: int) -> int:
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


def _boundary_loops(tris: np.ndarray, members: np.ndarray, is_boundary_he) -> list[list[int]]:
    """Chain the boundary half-edges of a set of triangles into closed loops (walking each vertex's fan)."""
    he_next: dict[tuple[int, int], tuple[int, int]] = {}
    owner = {}
    for ti in members:
        a, b, c = (int(v) for v in tris[ti])
        owner[(a, b)] = (b, c)
        owner[(b, c)] = (c, a)
        owner[(c, a)] = (a, b)
    boundary = [h for h in owner if is_boundary_he(h, owner)]
    for h in boundary:
        g = owner[h]  # next half-edge in the same triangle, leaving h's destination
        while not is_boundary_he(g, owner):
            g = owner[(g[1], g[0])]  # cross to the neighbour triangle, take its half-edge leaving the same vertex
        he_next[h] = g
    loops, seen = [], set()
    for h in boundary:
        if h in seen:
            continue
        loop, g = [], h
        while g not in seen:
            seen.add(g)
            loop.append(g[0])
            g = he_next[g]
        loops.append(loop)
    return loops


def _loop_area(points: np.ndarray, loop: list[int]) -> float:
    p = points[loop]
    q = np.roll(p, -1, axis=0)
    return 0.5 * float(np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))


def constrained_triangulation(pattern: CreasePattern, backend: str = "auto") -> PlanarTriangulation:
    """CDT of the sheet with every pattern segment as an edge, no Steiner points, outside and holes removed."""
    pattern.validate()
    backend = resolve_backend(backend)
    warnings: list[str] = []
    edges = pattern.edges
    if len(edges) == 0:
        raise PatternError("triangulation: the crease pattern has no segments")
    loops_ = edges[:, 0] == edges[:, 1]
    if loops_.any():
        raise PatternError(
            f"triangulation: pattern edge {int(np.flatnonzero(loops_)[0])} starts and ends at one vertex"
        )
    used = np.unique(edges)
    if len(used) < pattern.n_vertices:
        warnings.append(f"triangulation: {pattern.n_vertices - len(used)} isolated vertex(es) without segments dropped")
    remap = np.full(pattern.n_vertices, -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    pts = pattern.vertices[used]
    segs = remap[edges]
    key = np.sort(segs, axis=1)
    segment_of: dict[tuple[int, int], int] = {}
    for k, (i, j) in enumerate(key.tolist()):
        if (i, j) in segment_of:
            raise PatternError(f"triangulation: pattern edges {segment_of[(i, j)]} and {k} join the same two vertices")
        segment_of[(i, j)] = k
    if len(pts) < 3 or np.all(np.abs(orient(pts[0], pts[1], pts[2:])) <= 1e-12 * pattern.size**2):
        raise PatternError("triangulation: all pattern vertices lie on one line; there is no sheet to mesh")

    tris = _cdt_triangle(pts, segs) if backend == "triangle" else _cdt_mathutils(pts, segs)
    area = orient(pts[tris[:, 0]], pts[tris[:, 1]], pts[tris[:, 2]])
    tris[area < 0] = tris[area < 0][:, [0, 2, 1]]
    tris = tris[np.abs(area) > 0]
    missing = np.setdiff1d(np.arange(len(pts)), np.unique(tris))
    if len(missing):
        v = int(used[missing[0]])
        raise PatternError(
            f"triangulation: pattern vertex {v} at {pattern.vertices[v].round(4).tolist()} mm is not in the "
            "triangulation (it duplicates another vertex)"
        )
    tris, _ = legalise(pts, tris, set(segment_of))
    tris = _canonical_triangles(tris)
    # every constraint must be present
    sides = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    present = set(map(tuple, sides.tolist()))
    for (i, j), k in segment_of.items():
        if (i, j) not in present:
            where = pattern.sources[pattern.edge_polyline[k]] if pattern.sources else "no source"
            raise PatternError(
                f"triangulation: pattern edge {k} ({where})"
                " is not an edge of the triangulation: it overlaps another segment or passes through a vertex"
            )

    # regions: union triangles across non-constraint edges
    t = len(tris)
    owner = {}
    for ti, (a, b, c) in enumerate(tris.tolist()):
        owner[(a, b)] = ti
        owner[(b, c)] = ti
        owner[(c, a)] = ti
    parent = list(range(t))
    for (a, b), ti in owner.items():
        if a < b and (b, a) in owner and (a, b) not in segment_of:
            ra, rb = _find(parent, ti), _find(parent, owner[(b, a)])
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
    roots = np.array([_find(parent, i) for i in range(t)])
    region_ids, region = np.unique(roots, return_inverse=True)
    n_regions = len(region_ids)
    outside_seed = set()
    adjacency: dict[int, list[tuple[int, bool]]] = {r: [] for r in range(n_regions)}
    for (a, b), ti in owner.items():
        if (b, a) not in owner:
            if (min(a, b), max(a, b)) not in segment_of:
                outside_seed.add(int(region[ti]))
            continue
        if a < b and (a, b) in segment_of:
            r1, r2 = int(region[ti]), int(region[owner[(b, a)]])
            if r1 != r2:
                toggles = pattern.assignments[segment_of[(a, b)]] == "B"
                adjacency[r1].append((r2, toggles))
                adjacency[r2].append((r1, toggles))
    inside = np.full(n_regions, -1, dtype=np.int64)
    queue = []
    for r in sorted(outside_seed):
        inside[r] = 0
        queue.append(r)
    # regions that meet the hull only through constraint edges: the hull edge itself is a border (paper side) or a
    # crease; treat the unbounded side as outside, so a region whose hull edge is a B segment is inside.
    for (a, b), ti in owner.items():
        if (b, a) not in owner and (min(a, b), max(a, b)) in segment_of:
            r = int(region[ti])
            if inside[r] < 0:
                inside[r] = 1 if pattern.assignments[segment_of[(min(a, b), max(a, b))]] == "B" else 0
                queue.append(r)
    conflict = False
    while queue:
        r = queue.pop()
        for s, toggles in adjacency[r]:
            want = inside[r] ^ int(toggles)
            if inside[s] < 0:
                inside[s] = want
                queue.append(s)
            elif inside[s] != want:
                conflict = True
    if conflict:
        warnings.append("triangulation: border lines do not separate paper from outside consistently; kept as paper")
    keep_region = inside == 1
    if not keep_region.any():
        raise PatternError("triangulation: no paper left: the border does not enclose any region")
    keep_tri = keep_region[region]
    tris = tris[keep_tri]
    # renumber regions in order of first triangle (triangles are canonically sorted)
    old = region[keep_tri]
    _, first = np.unique(old, return_index=True)
    order = np.argsort(first)
    new_of_old = np.full(n_regions, -1, dtype=np.int64)
    new_of_old[np.unique(old)[order]] = np.arange(len(order))
    tri_region = new_of_old[old]

    # drop vertices no longer used (only outside the paper), keep order
    used2 = np.unique(tris)
    if len(used2) < len(pts):
        warnings.append(f"triangulation: {len(pts) - len(used2)} vertex(es) outside the paper dropped")
    remap2 = np.full(len(pts), -1, dtype=np.int64)
    remap2[used2] = np.arange(len(used2))
    tris = remap2[tris]
    pts2 = pts[used2]
    vertex_source = used[used2]
    seg2 = {}
    for (i, j), k in segment_of.items():
        a, b = remap2[i], remap2[j]
        if a >= 0 and b >= 0:
            seg2[(int(min(a, b)), int(max(a, b)))] = k

    faces, face_loops, simple = [], [], []
    for f in range(len(order)):
        members = np.flatnonzero(tri_region == f)

        def is_boundary(h, own, _seg=seg2):
            return (h[1], h[0]) not in own or (min(h), max(h)) in _seg

        loops = _boundary_loops(tris, members, is_boundary)
        areas = [_loop_area(pts2, lp) for lp in loops]
        outer = int(np.argmax(areas))
        loops = [loops[outer]] + [lp for k, lp in enumerate(loops) if k != outer]
        faces.append(np.asarray(loops[0], dtype=np.int64))
        face_loops.append([np.asarray(lp, dtype=np.int64) for lp in loops])
        simple.append(len(loops) == 1 and len(set(loops[0])) == len(loops[0]))
    return PlanarTriangulation(
        vertices=pts2,
        vertex_source=vertex_source,
        triangles=tris,
        triangle_region=tri_region,
        faces=faces,
        face_loops=face_loops,
        face_simple=np.asarray(simple, dtype=bool),
        segment_of=seg2,
        backend=backend,
        warnings=warnings,
    )


def split_cuts(
    vertices: np.ndarray, triangles: np.ndarray, cut_pairs: set[tuple[int, int]]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Duplicate vertices along cuts (Origami Simulator ``splitCuts``).

    Triangle corners at one vertex are grouped into fans connected across non-cut interior edges; every fan after
    the first gets a copy of the vertex. Returns ``(vertices, triangles, vertex_origin)`` where ``vertex_origin``
    maps each output vertex to its input vertex.
    """
    n = len(vertices)
    if not cut_pairs:
        return vertices, triangles, np.arange(n)
    t = len(triangles)
    corner_parent = list(range(3 * t))
    where = {}
    for ti, tri in enumerate(triangles.tolist()):
        for k in range(3):
            where[(tri[k], tri[(k + 1) % 3])] = (ti, k)
    for (a, b), (ti, k) in where.items():
        if (b, a) in where and (min(a, b), max(a, b)) not in cut_pairs:
            tj, kj = where[(b, a)]
            # corner of a in ti is k; in tj, a is the destination of b→a: corner (kj + 1) % 3
            for c1, c2 in ((3 * ti + k, 3 * tj + (kj + 1) % 3), (3 * ti + (k + 1) % 3, 3 * tj + kj)):
                r1, r2 = _find(corner_parent, c1), _find(corner_parent, c2)
                if r1 != r2:
                    corner_parent[max(r1, r2)] = min(r1, r2)
    flat = triangles.reshape(-1)
    roots = np.array([_find(corner_parent, c) for c in range(3 * t)])
    new_index = {}
    first_root = {}
    origin = list(range(n))
    out = np.empty(3 * t, dtype=np.int64)
    for c in np.argsort(roots, kind="stable"):
        v, r = int(flat[c]), int(roots[c])
        if r not in new_index:
            if v not in first_root:
                first_root[v] = r
                new_index[r] = v
            else:
                new_index[r] = len(origin)
                origin.append(v)
        out[c] = new_index[r]
    origin = np.asarray(origin, dtype=np.int64)
    return vertices[origin], out.reshape(-1, 3), origin
