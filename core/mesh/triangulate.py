"""Constrained Delaunay triangulation of a crease pattern, without interior (Steiner) points (paper §3.2).

Every crease and border segment becomes a triangle edge; the only vertices are the pattern's own (the mesh stage
first puts vertices on long straight creases that would fan needles, :mod:`.needles`, and triangulates that
pattern). The paper uses CDT instead of ear clipping because Delaunay triangles are "fatter": fewer long fans
meeting at one vertex, which would act as cone rulings.

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
   crossing any other segment keeps it. Outside regions and holes are dropped. A pattern *without* border segments
   is taken as Origami Simulator takes it: every region the drawn segments enclose is paper, and the segments
   between paper and outside become the border (``outline_edges``, with a warning).

Cuts are split afterwards (:func:`split_cuts`, Origami Simulator's ``splitCuts``): each cut becomes two border edges
and each vertex is duplicated once per extra fan of triangles separated by cuts.

Speed: everything after the backend works on half-edge arrays (:func:`half_edges`, h = 3·triangle + k, twins found
by sorting): the Delaunay screening, the constraint check, region labelling
(:func:`..pattern.polylines.connected_components`), the toggles and the face loops (:func:`face_loops`) are
vectorised; Python loops remain only for the (few) Lawson flips, the region breadth-first search and the chaining of
boundary half-edges into loops.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from .. import load_bpy
from ..pattern.model import CreasePattern, PatternError
from ..pattern.polylines import connected_components, point_segment_distance

BACKENDS = ("auto", "triangle", "mathutils")

NO_BORDER = (
    "crease pattern has no border (B) segments: the sheet's outline must be drawn, as a closed curve with the role "
    "Border (black in SVG), around the creases, or the drawn segments must enclose the paper (their outer boundary is "
    "then taken as the border); these enclose no region"
)
"""The one line for a pattern without border whose segments enclose nothing (a lone line, a cross)."""

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
    * ``outline_edges``: pattern edges taken as the border because the pattern has none (the outer boundary of the
      drawn segments, as Origami Simulator does); empty when the pattern has a border.
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
    outline_edges: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))


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
        raise _CrossingError(np.asarray(out["vertices"][len(points)], dtype=float))
    return np.asarray(out["triangles"], dtype=np.int64)


class _CrossingError(PatternError):
    """Two segments cross or touch away from a vertex (Triangle added one there, at ``at``): named by the caller."""

    def __init__(self, at: np.ndarray) -> None:
        super().__init__(f"triangulation: segments cross or touch near ({at[0]:.4g}, {at[1]:.4g}) mm")
        self.at = at


def _cdt_mathutils(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    load_bpy()  # mathutils needs bpy imported first in the bpy module
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


def _incircle_scalar(a: list[float], b: list[float], c: list[float], d: list[float]) -> float:
    """:func:`incircle` for one quad in plain Python floats: the same operations in the same order, so the same
    value to the last bit (``np.mean`` over 4 rows adds them in sequence), without numpy's per-call overhead."""
    cx = (((a[0] + b[0]) + c[0]) + d[0]) / 4.0
    cy = (((a[1] + b[1]) + c[1]) + d[1]) / 4.0
    scale = max(abs(p[k] - m) for p in (a, b, c, d) for k, m in ((0, cx), (1, cy))) + 1e-300
    adx, ady = (a[0] - d[0]) / scale, (a[1] - d[1]) / scale
    bdx, bdy = (b[0] - d[0]) / scale, (b[1] - d[1]) / scale
    cdx, cdy = (c[0] - d[0]) / scale, (c[1] - d[1]) / scale
    adl = adx * adx + ady * ady
    bdl = bdx * bdx + bdy * bdy
    cdl = cdx * cdx + cdy * cdy
    return adl * (bdx * cdy - bdy * cdx) - bdl * (adx * cdy - ady * cdx) + cdl * (adx * bdy - ady * bdx)


def legalise(points: np.ndarray, tris: np.ndarray, constrained: set[tuple[int, int]]) -> tuple[np.ndarray, int]:
    """Lawson flips until every non-constraint edge is locally Delaunay, with deterministic cocircular tie-breaks.

    A quad whose in-circle value is within :data:`_TIE_TOLERANCE` of zero is a tie: its diagonal must touch the
    smallest vertex index of the quad. Returns the new triangles and the number of flips. Every interior edge is
    screened at once on half-edge arrays; the Python flip loop only runs over the (usually few) edges that are not
    clearly Delaunay (ties and offenders) and the neighbours of the flips it makes.

    The tolerance makes near-cocircular points (a circle's nodes) a canonical fan whatever the backend gave, but it
    is not a consistent order: among several nearly cocircular points some quads fall just outside it (decided by
    geometry) and some inside (by index), and the two can disagree round a cycle — a fuzzed Bézier border with two
    creases flipped the same edges for ever ("did not terminate", a RuntimeError that reached the user). When the
    flips exceed their bound the pass is run again from the backend's triangles with exact predicates (rational
    arithmetic on the float coordinates; a tie is then an exact zero, decided by index), for which Lawson's
    flips terminate. Meshes that never cycled are unchanged.
    """
    try:
        return _lawson(points, tris, constrained, exact=False)
    except _FlipCycleError:
        return _lawson(points, tris, constrained, exact=True)


class _FlipCycleError(Exception):
    """Lawson flips beyond their bound: the tolerance's decisions went round a cycle."""


def _lawson(
    points: np.ndarray, tris: np.ndarray, constrained: set[tuple[int, int]], exact: bool
) -> tuple[np.ndarray, int]:
    """:func:`legalise`'s flips, with the tolerance or (``exact``) with exact predicates."""
    tris = np.asarray(tris, dtype=np.int64).reshape(-1, 3)
    n = len(points)
    empty = np.zeros(0, dtype=np.int64)
    org, dst, twin, _ = half_edges(tris, n, empty)
    opp = np.roll(tris, -2, axis=1).reshape(-1)
    cand = np.flatnonzero((org < dst) & (twin >= 0))  # each interior edge once, in half-edge order
    if len(cand) == 0:
        return tris, 0
    ca, cb, cc, cd = org[cand], dst[cand], opp[cand], opp[twin[cand]]
    val = incircle(points[ca], points[cb], points[cc], points[cd])
    pick = np.flatnonzero(val >= (-1e-6 if exact else -_TIE_TOLERANCE))  # exact: screen generously
    if len(pick) == 0:
        return tris, 0
    stack = list(zip(ca[pick].tolist(), cb[pick].tolist(), strict=True))

    xy = points.tolist()
    fr = [(Fraction(x), Fraction(y)) for x, y in xy] if exact else []
    tris_l = tris.tolist()
    owner: dict[tuple[int, int], int] = {}
    for ti, (a, b, c) in enumerate(tris_l):
        owner[(a, b)] = ti
        owner[(b, c)] = ti
        owner[(c, a)] = ti

    def third(ti: int, a: int, b: int) -> int:
        t = tris_l[ti]
        return t[0] + t[1] + t[2] - a - b

    def wants_flip(a: int, b: int) -> bool:
        """Edge a→b (t1 on its left) should become the other diagonal."""
        if ((a, b) if a < b else (b, a)) in constrained:
            return False
        t1, t2 = owner.get((a, b), -1), owner.get((b, a), -1)
        if t1 < 0 or t2 < 0:
            return False
        c, d = third(t1, a, b), third(t2, b, a)
        pts = fr if exact else xy
        pa, pb, pc, pd = pts[a], pts[b], pts[c], pts[d]
        # the quad a, d, b, c must be strictly convex: both new triangles (c, a, d), (d, b, c) counter-clockwise
        if _orient2(pc, pa, pd) <= 0 or _orient2(pd, pb, pc) <= 0:
            return False
        if exact:  # a tie is an exact zero
            val = _incircle_exact(pa, pb, pc, pd)
            return val > 0 or (val == 0 and min(c, d) < min(a, b))
        val = _incircle_scalar(pa, pb, pc, pd)
        if val > _TIE_TOLERANCE:
            return True
        if val < -_TIE_TOLERANCE:
            return False
        return min(c, d) < min(a, b)

    flips = 0
    limit = 50 * len(tris_l) + 100
    while stack:
        a, b = stack.pop()
        if (a, b) not in owner:
            a, b = b, a
            if (a, b) not in owner:
                continue
        if not wants_flip(a, b):
            continue
        flips += 1
        if flips > limit:  # the tolerance's decisions cycle (see legalise); exact predicates terminate
            if exact:  # pragma: no cover - Lawson's flips with exact predicates terminate
                raise RuntimeError("triangulation: Delaunay legalisation did not terminate")
            raise _FlipCycleError
        t1, t2 = owner[(a, b)], owner[(b, a)]
        c, d = third(t1, a, b), third(t2, b, a)
        for e in ((a, b), (b, c), (c, a), (b, a), (a, d), (d, b)):
            owner.pop(e, None)
        tris_l[t1] = [c, a, d]
        tris_l[t2] = [d, b, c]
        for ti in (t1, t2):
            x, y, z = tris_l[ti]
            owner[(x, y)] = ti
            owner[(y, z)] = ti
            owner[(z, x)] = ti
        stack += [(a, d), (d, b), (b, c), (c, a)]
    return np.asarray(tris_l, dtype=np.int64).reshape(-1, 3), flips


def _incircle_exact(a, b, c, d) -> Fraction:
    """The in-circle determinant of ``d`` against CCW ``(a, b, c)`` in exact rational arithmetic (its sign only
    matters: > 0 inside)."""
    adx, ady = a[0] - d[0], a[1] - d[1]
    bdx, bdy = b[0] - d[0], b[1] - d[1]
    cdx, cdy = c[0] - d[0], c[1] - d[1]
    adl = adx * adx + ady * ady
    bdl = bdx * bdx + bdy * bdy
    cdl = cdx * cdx + cdy * cdy
    return adl * (bdx * cdy - bdy * cdx) - bdl * (adx * cdy - ady * cdx) + cdl * (adx * bdy - ady * bdx)


def _orient2(a: list[float], b: list[float], c: list[float]) -> float:
    """:func:`orient` for one triple of plain floats (same operations)."""
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])


# ----------------------------------------------------------------------------------------------------------------
# regions (crease-pattern faces)
# ----------------------------------------------------------------------------------------------------------------


def _find(parent: list[int], i: int) -> int:
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


def _loop_area(points: np.ndarray, loop: list[int]) -> float:
    p = points[loop]
    q = np.roll(p, -1, axis=0)
    return 0.5 * float(np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))


def half_edges(tris: np.ndarray, n_vertices: int, seg_code: np.ndarray) -> tuple[np.ndarray, ...]:
    """Half-edge arrays of a triangulation: h = 3·triangle + k runs from corner k to corner k + 1.

    Returns ``(org, dst, twin, is_seg)``: origin and destination vertex, the opposite half-edge (−1 on the hull)
    and whether the half-edge lies on a pattern segment (``seg_code`` = sorted ``i·n + j`` codes with i < j).
    """
    n = np.int64(n_vertices)
    org = tris.reshape(-1)
    dst = np.roll(tris, -1, axis=1).reshape(-1)
    code = org * n + dst
    order = np.argsort(code, kind="stable")
    sorted_code = code[order]
    twin_code = dst * n + org
    pos = np.clip(np.searchsorted(sorted_code, twin_code), 0, max(len(code) - 1, 0))
    twin = np.where(sorted_code[pos] == twin_code, order[pos], -1) if len(code) else np.zeros(0, dtype=np.int64)
    is_seg = np.isin(np.minimum(org, dst) * n + np.maximum(org, dst), seg_code)
    return org, dst, twin, is_seg


def face_loops(
    points: np.ndarray, tris: np.ndarray, tri_face: np.ndarray, n_faces: int, seg_code: np.ndarray
) -> list[list[list[int]]]:
    """Boundary loops of every crease-pattern face (the triangles of each face bounded by segments or the hull).

    The loops of a face are listed in the order of their first half-edge (triangle order, then corner order), each
    starting there (the order of a per-face walk over the triangles). The "next boundary half-edge" is found
    for all half-edges at once by turning around each vertex's fan (vectorised); only the final chaining into loops
    is a Python pass over the boundary half-edges.
    """
    org, _dst, twin, is_seg = half_edges(tris, len(points), seg_code)
    boundary = (twin < 0) | is_seg
    h_all = np.arange(len(org))
    nxt_in_tri = h_all - h_all % 3 + (h_all % 3 + 1) % 3
    bh = np.flatnonzero(boundary)
    cur = nxt_in_tri[bh]
    inner = ~boundary[cur]
    while inner.any():  # cross to the neighbour triangle, take its half-edge leaving the same vertex
        cur[inner] = nxt_in_tri[twin[cur[inner]]]
        inner[inner] = ~boundary[cur[inner]]
    nxt = np.full(len(org), -1, dtype=np.int64)
    nxt[bh] = cur
    nxt_l, org_l = nxt.tolist(), org.tolist()
    face_of = np.repeat(tri_face, 3).tolist()
    loops: list[list[list[int]]] = [[] for _ in range(n_faces)]
    seen = bytearray(len(org))
    for h in bh.tolist():
        if seen[h]:
            continue
        loop, g = [], h
        while not seen[g]:
            seen[g] = 1
            loop.append(org_l[g])
            g = nxt_l[g]
        loops[face_of[h]].append(loop)
    return loops


def _outer_first(points: np.ndarray, loops: list[list[int]]) -> list[list[int]]:
    """The loop with the largest signed area (the CCW outer boundary) first, the others after it in order."""
    if len(loops) == 1:
        return loops
    areas = [_loop_area(points, lp) for lp in loops]
    outer = int(np.argmax(areas))
    return [loops[outer]] + [lp for k, lp in enumerate(loops) if k != outer]


@dataclass
class _Segments:
    """The pattern's segments on its used vertices: ``used`` pattern vertex of each point, the points, the segments
    as point pairs (``key`` sorted per row, row k = pattern edge k) and ``segment_of`` {(i, j): pattern edge}."""

    used: np.ndarray
    points: np.ndarray
    segments: np.ndarray
    key: np.ndarray
    segment_of: dict[tuple[int, int], int]


def _pattern_segments(pattern: CreasePattern, warnings: list[str]) -> _Segments:
    """Step 0: the pattern's vertices that lie on a segment, and its segments; refuse what cannot be meshed (loops,
    two segments between one pair of vertices, every vertex on one line)."""
    edges = pattern.edges
    if len(edges) == 0:
        raise PatternError("triangulation: the crease pattern has no segments")
    loops_ = edges[:, 0] == edges[:, 1]
    if loops_.any():
        raise PatternError(
            f"triangulation: pattern edge {_named(pattern, np.flatnonzero(loops_)[0])} starts and ends at one vertex"
        )
    used = np.unique(edges)
    if len(used) < pattern.n_vertices:
        lone = np.setdiff1d(np.arange(pattern.n_vertices), used)
        at = ", ".join(f"({x:.3f}, {y:.3f})" for x, y in pattern.vertices[lone[:3]].tolist())
        more = f" and {len(lone) - 3} more" if len(lone) > 3 else ""
        warnings.append(f"triangulation: {len(lone)} isolated vertex(es) without segments dropped, at {at} mm{more}")
    remap = np.full(pattern.n_vertices, -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    pts = pattern.vertices[used]
    segs = remap[edges]
    key = np.sort(segs, axis=1)
    segment_of: dict[tuple[int, int], int] = {}
    for k, (i, j) in enumerate(key.tolist()):
        if (i, j) in segment_of:
            both = f"{_named(pattern, segment_of[(i, j)])} and {_named(pattern, k)}"
            raise PatternError(f"triangulation: pattern edges {both} join the same two vertices")
        segment_of[(i, j)] = k
    if len(pts) < 3 or np.all(np.abs(orient(pts[0], pts[1], pts[2:])) <= 1e-12 * pattern.size**2):
        if not np.any(pattern.assignments == "B"):
            raise PatternError(NO_BORDER)
        raise PatternError("triangulation: all pattern vertices lie on one line; there is no sheet to mesh")
    return _Segments(used, pts, segs, key, segment_of)


def _triangulate_hull(pattern: CreasePattern, sg: _Segments, backend: str) -> np.ndarray:
    """Steps 1–2: the backend's CDT of the convex hull, CCW, every vertex present, made canonical (Lawson pass with
    deterministic tie breaks, sorted)."""
    pts = sg.points
    _, first, inverse = np.unique(pts, axis=0, return_index=True, return_inverse=True)
    repeated = np.flatnonzero(first[inverse.reshape(-1)] != np.arange(len(pts)))
    if len(repeated):
        # refused before the backend: Triangle drops a repeated vertex, and crashed (segfault) on one such input
        v = int(sg.used[repeated[0]])
        raise PatternError(
            f"triangulation: pattern vertex {v} at {pattern.vertices[v].round(4).tolist()} mm is not in the "
            "triangulation (it duplicates another vertex)"
        )
    try:
        tris = _cdt_triangle(pts, sg.segments) if backend == "triangle" else _cdt_mathutils(pts, sg.segments)
    except _CrossingError as crossing:
        # a drawing's crossings are split when it is discretised; a FOLD file's edges are taken as they are
        a, b = pts[sg.segments[:, 0]], pts[sg.segments[:, 1]]
        near = np.argsort(point_segment_distance(np.broadcast_to(crossing.at, a.shape), a, b), kind="stable")[:2]
        named = " and ".join(_named(pattern, sg.segment_of[tuple(sorted(sg.segments[k].tolist()))]) for k in near)
        raise PatternError(
            f"triangulation: pattern edges {named} cross or touch near ({crossing.at[0]:.4g}, {crossing.at[1]:.4g})"
            " mm away from a vertex; a crease pattern's edges may meet only at their ends (split them there)"
        ) from None
    area = orient(pts[tris[:, 0]], pts[tris[:, 1]], pts[tris[:, 2]])
    tris[area < 0] = tris[area < 0][:, [0, 2, 1]]
    tris = tris[np.abs(area) > 0]
    missing = np.setdiff1d(np.arange(len(pts)), np.unique(tris))
    if len(missing):
        v = int(sg.used[missing[0]])
        raise PatternError(
            f"triangulation: pattern vertex {v} at {pattern.vertices[v].round(4).tolist()} mm is not in the "
            "triangulation (it duplicates another vertex)"
        )
    tris, _ = legalise(pts, tris, set(sg.segment_of))
    return _canonical_triangles(tris)


def _named(pattern: CreasePattern, k: int) -> str:
    """Pattern edge ``k`` for a message, with the stroke or file edge it came from (a FOLD file's edges are
    renumbered where its dense polylines were thinned, so the index alone may not be the file's)."""
    k = int(k)
    src = int(pattern.edge_polyline[k]) if k < len(pattern.edge_polyline) else -1
    return f"{k} ({pattern.sources[src] if 0 <= src < len(pattern.sources) else 'no source'})"


def _check_constraints(
    pattern: CreasePattern, sg: _Segments, seg_code: np.ndarray, org: np.ndarray, dst: np.ndarray
) -> None:
    """Every pattern segment must be a triangle side (else it overlaps another or passes through a vertex)."""
    n_pts = np.int64(len(sg.points))
    present = np.isin(seg_code, np.minimum(org, dst) * n_pts + np.maximum(org, dst))
    if not present.all():
        i, j = divmod(int(seg_code[np.flatnonzero(~present)[0]]), int(n_pts))
        raise PatternError(
            f"triangulation: pattern edge {_named(pattern, sg.segment_of[(i, j)])}"
            " is not an edge of the triangulation: it overlaps another segment or passes through a vertex"
        )


def _region_labels(he: tuple[np.ndarray, ...], n_tris: int) -> np.ndarray:
    """Region of every triangle: triangles connected across non-segment edges, numbered by their smallest one."""
    org, dst, twin, is_seg = he
    tri_of = np.arange(3 * n_tris) // 3
    inner = (twin >= 0) & ~is_seg & (org < dst)
    roots = connected_components(n_tris, tri_of[inner], tri_of[twin[inner]])
    return np.unique(roots, return_inverse=True)[1].reshape(-1)


def _paper_triangles(
    pattern: CreasePattern,
    sg: _Segments,
    seg_code: np.ndarray,
    he: tuple[np.ndarray, ...],
    n_tris: int,
    warnings: list[str],
) -> tuple[np.ndarray, np.ndarray]:
    """Step 3: label the regions (triangles connected across non-constraint edges, labelled by their smallest
    triangle) inside or outside the paper. Returns ``(keep_tri, region)``: the triangles on paper, and each
    triangle's region."""
    org, dst, twin, is_seg = he
    n_pts = np.int64(len(sg.points))
    tri_of = np.arange(3 * n_tris) // 3
    region = _region_labels(he, n_tris)
    n_regions = int(region.max()) + 1
    hull = twin < 0
    outside_seed = set(region[tri_of[hull & ~is_seg]].tolist())
    adjacency: list[list[tuple[int, bool]]] = [[] for _ in range(n_regions)]
    key = sg.key
    seg_sorted_k = np.argsort(key[:, 0] * n_pts + key[:, 1])  # pattern edge k is row k of key; codes are unique
    is_border_seg = pattern.assignments[seg_sorted_k] == "B"  # aligned with seg_code
    he_code = np.minimum(org, dst) * n_pts + np.maximum(org, dst)
    cross = np.flatnonzero((twin >= 0) & is_seg & (org < dst))
    r1s, r2s = region[tri_of[cross]].tolist(), region[tri_of[twin[cross]]].tolist()
    toggles_l = is_border_seg[np.searchsorted(seg_code, he_code[cross])].tolist()
    for r1, r2, toggles in zip(r1s, r2s, toggles_l, strict=True):
        if r1 != r2:
            adjacency[r1].append((r2, toggles))
            adjacency[r2].append((r1, toggles))
    inside = [-1] * n_regions
    queue = []
    for r in sorted(outside_seed):
        inside[r] = 0
        queue.append(r)
    # regions that meet the hull only through constraint edges: the hull edge itself is a border (paper side) or a
    # crease; treat the unbounded side as outside, so a region whose hull edge is a B segment is inside.
    hull_seg = np.flatnonzero(hull & is_seg)
    hull_border = is_border_seg[np.searchsorted(seg_code, he_code[hull_seg])].tolist()
    for r, border in zip(region[tri_of[hull_seg]].tolist(), hull_border, strict=True):
        if inside[r] < 0:
            inside[r] = 1 if border else 0
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
    keep_region = np.asarray(inside) == 1
    if not keep_region.any():
        raise PatternError("triangulation: no paper left: the border does not enclose any region")
    return keep_region[region], region


def _outline_regions(region: np.ndarray, he: tuple[np.ndarray, ...], n_tris: int) -> tuple[np.ndarray, np.ndarray]:
    """Step 3 without any border segment (as Origami Simulator): the paper is everything the drawn segments enclose.

    Regions reached from the convex hull through a non-segment edge are outside, all others paper. Returns
    ``(keep_tri, outline)``: the triangles on paper and the half-edges (org < dst, or on the hull) of the segments
    between paper and outside, which become the border."""
    org, dst, twin, is_seg = he
    tri_of = np.arange(3 * n_tris) // 3
    hull = twin < 0
    outside = np.zeros(int(region.max()) + 1, dtype=bool)
    outside[region[tri_of[hull & ~is_seg]]] = True
    keep_tri = ~outside[region]
    if not keep_tri.any():
        raise PatternError(NO_BORDER)
    paper_he = keep_tri[tri_of]
    twin_paper = np.where(twin >= 0, keep_tri[tri_of[np.maximum(twin, 0)]], False)
    outline = np.flatnonzero(is_seg & paper_he & ~twin_paper)
    return keep_tri, outline


def _renumber_regions(region: np.ndarray) -> tuple[np.ndarray, int]:
    """Regions numbered in order of their first triangle (triangles are canonically sorted): ``(index, count)``."""
    _, first = np.unique(region, return_index=True)
    order = np.argsort(first)
    new_of_old = np.full(int(region.max()) + 1 if len(region) else 0, -1, dtype=np.int64)
    new_of_old[np.unique(region)[order]] = np.arange(len(order))
    return new_of_old[region], len(order)


def _drop_unused_vertices(
    sg: _Segments, tris: np.ndarray, warnings: list[str]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[tuple[int, int], int]]:
    """Vertices no longer used (only outside the paper) dropped, order kept: ``(points, vertex_source, triangles,
    segment_of)`` renumbered."""
    pts = sg.points
    used2 = np.unique(tris)
    if len(used2) < len(pts):
        warnings.append(f"triangulation: {len(pts) - len(used2)} vertex(es) outside the paper dropped")
    remap2 = np.full(len(pts), -1, dtype=np.int64)
    remap2[used2] = np.arange(len(used2))
    seg_ij = np.array(list(sg.segment_of), dtype=np.int64).reshape(-1, 2)
    seg_k = np.fromiter(sg.segment_of.values(), dtype=np.int64, count=len(sg.segment_of))
    ra, rb = remap2[seg_ij[:, 0]], remap2[seg_ij[:, 1]]
    keep = (ra >= 0) & (rb >= 0)
    lo2, hi2 = np.minimum(ra, rb)[keep].tolist(), np.maximum(ra, rb)[keep].tolist()
    seg2 = dict(zip(zip(lo2, hi2, strict=True), seg_k[keep].tolist(), strict=True))
    return pts[used2], sg.used[used2], remap2[tris], seg2


def constrained_triangulation(pattern: CreasePattern, backend: str = "auto") -> PlanarTriangulation:
    """CDT of the sheet with every pattern segment as an edge, no Steiner points, outside and holes removed.

    The steps of the module docstring: the pattern's segments (:func:`_pattern_segments`), the CDT of their hull made
    canonical (:func:`_triangulate_hull`), the constraint check, the paper regions (:func:`_paper_triangles`), then
    renumbering and the crease-pattern face loops.
    """
    pattern.validate()
    backend = resolve_backend(backend)
    warnings: list[str] = []
    sg = _pattern_segments(pattern, warnings)
    tris = _triangulate_hull(pattern, sg, backend)
    n_pts = np.int64(len(sg.points))
    seg_code = np.unique(sg.key[:, 0] * n_pts + sg.key[:, 1])
    he = half_edges(tris, len(sg.points), seg_code)
    _check_constraints(pattern, sg, seg_code, he[0], he[1])
    outline_edges = np.zeros(0, dtype=np.int64)
    if np.any(pattern.assignments == "B"):
        keep_tri, region = _paper_triangles(pattern, sg, seg_code, he, len(tris), warnings)
    else:
        region = _region_labels(he, len(tris))
        keep_tri, outline = _outline_regions(region, he, len(tris))
        code = np.minimum(he[0][outline], he[1][outline]) * n_pts + np.maximum(he[0][outline], he[1][outline])
        pairs = np.column_stack(np.divmod(np.unique(code), n_pts)).tolist()
        outline_edges = np.array(sorted(sg.segment_of[(i, j)] for i, j in pairs), dtype=np.int64)
        names = sorted(
            {pattern.sources[pattern.edge_polyline[k]] for k in outline_edges.tolist()} if pattern.sources else set()
        )
        shown = ", ".join(names[:4]) + (f" and {len(names) - 4} more" if len(names) > 4 else "")
        creases = int(np.count_nonzero(pattern.assignments[outline_edges] != "C"))  # cuts never folded anyway
        lost = f"; the {creases} crease segment(s) among them no longer fold" if creases else ", all cuts"
        warnings.append(
            f"no border (B) segments drawn: took the outer boundary of the drawn segments as the border, as Origami "
            f"Simulator does ({len(outline_edges)} segment(s){', from ' + shown if shown else ''}{lost})"
        )
    tris = tris[keep_tri]
    tri_region, n_faces = _renumber_regions(region[keep_tri])
    pts2, vertex_source, tris, seg2 = _drop_unused_vertices(sg, tris, warnings)

    seg2_code = np.array(sorted(i * len(pts2) + j for i, j in seg2), dtype=np.int64)
    faces, face_loops_, simple = [], [], []
    for loops in face_loops(pts2, tris, tri_region, n_faces, seg2_code):
        loops = _outer_first(pts2, loops)
        faces.append(np.asarray(loops[0], dtype=np.int64))
        face_loops_.append([np.asarray(lp, dtype=np.int64) for lp in loops])
        simple.append(len(loops) == 1 and len(set(loops[0])) == len(loops[0]))
    return PlanarTriangulation(
        vertices=pts2,
        vertex_source=vertex_source,
        triangles=tris,
        triangle_region=tri_region,
        faces=faces,
        face_loops=face_loops_,
        face_simple=np.asarray(simple, dtype=bool),
        segment_of=seg2,
        backend=backend,
        warnings=warnings,
        outline_edges=outline_edges,
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
