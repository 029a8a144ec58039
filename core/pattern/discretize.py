"""Discretisation of a drawn crease pattern into straight segments (paper §3.1), and its planar clean-up.

Steps, in order:

1. **Curves.** Every curved segment (cubic Bézier, elliptical arc) is split at equal *parameter* steps, with the
   smallest count for which every chord is at most ``interval``; then, as in the paper, the curve's parameter
   midpoint is inserted wherever its distance from the chord exceeds ``tolerance``, repeatedly, until none is
   left. Each segment is refined on its own, vectorised over its chords.
2. **Straight segments.** Straight *border* segments are split into ⌈length / interval⌉ equal pieces so the
   triangulation has border vertices to attach rulings to; straight creases are kept whole here (the
   triangulation splits those that would fan needles, :mod:`..mesh.needles`, at the pattern's ``interval``).
   Polyline input keeps its drawn vertices, except where it is sampled far finer than the interval (step 6).
3. **Planar arrangement.** Vertices closer than ``merge_tolerance`` are merged (into the first representative, as
   Origami Simulator does; border vertices come first so the outline never moves); crossing segments (X) and
   endpoints lying on another segment (T) are split at the intersection (a computed crossing within
   :data:`SNAP_FACTOR` merge tolerances of an existing vertex snaps to it, as does one within the merge tolerance of
   an end of each; one inside a segment but within the merge tolerance of the other's end splits the first at that
   end); zero-length and duplicate segments are removed. Candidate pairs come from a uniform grid over the segments'
   bounding boxes, so the work grows with the number of nearby pairs, not with E².
4. **Outside pieces.** Border pieces that are no part of an outline (a black slit from the edge, a black line
   across or loose inside the sheet) are read as cuts, with a warning naming them (:func:`_stray_border_as_cuts`).
   If the border is then closed, crease pieces lying outside it (creases drawn slightly past the
   edge of the sheet) are removed, with a warning; a crossing on the border never snaps to a vertex off it, so the
   outline stays where it was drawn. Free ends of creases (not cuts) that stop just short of the border
   (:data:`SHORT_OF_BORDER_FRACTION`) are moved onto it (onto a corner they are drawn towards or stop beside,
   :func:`_corner_ahead`), with a warning (:func:`_snap_short_ends`); crease ends
   that stop as short (of the sheet's width) of another stroke ahead of them are drawn on to it (unless the piece
   drawn on would cross a stroke or pass within the merge tolerance of a vertex: :func:`_join_tangles`), and pieces
   drawn as far past a crossing to a free end are removed (:func:`_join_near_misses`).
5. **Samples beside junctions.** A curve sample point left a small fraction of a chord from a crossing or T-junction
   on its curve is removed where the curve stays within ``tolerance`` of the new chord (the short piece would force
   sliver triangles; :func:`_drop_samples_beside_junctions`).
6. **Flattened curves and border pieces.** Chains of segments that follow a curve, drawn with straight pieces only
   (polylines, separate lines), are marked as curve pieces as a Bézier's are, so the ruling swaps score them
   (:func:`.polylines.flattened_curves`); a stroke with a Bézier or an arc in it says which of its pieces are
   straight. A polyline sampled far finer than the interval (median piece under a quarter of it) is thinned to the
   paper's sampling, drawn vertices kept (:func:`.polylines.thin_dense_polylines`). Border edges drawn straight (a
   flattened curve's chords too), now running between the junctions the designer drew, are split into
   ⌈length / interval⌉ equal pieces (so no sliver is left beside a junction).

Defaults follow the paper (150 mm sheet: interval 7 mm, tolerance 0.07 mm) and are **scale-aware**: multiplied by
sheet size / 150 mm, where the sheet size is the largest extent of the border's bounding box (of all curves if
there is no border). See :data:`MERGE_PER_150` for the merge tolerance.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from dataclasses import dataclass, fields, replace

import numpy as np

from .. import run_to_end
from .model import CreaseCurve, CreasePattern, CurveSegment, PatternError
from .polylines import (
    connected_components,
    flattened_curves,
    point_segment_distance,
    segment_foot,
    thin_dense_polylines,
)

REFERENCE_SIZE_MM = 150.0
"""Sheet width the paper's parameters were chosen for (§4)."""

INTERVAL_PER_150 = 7.0
"""Paper §4: maximum chord length (and border piece length) for a 150 mm sheet, mm."""

TOLERANCE_PER_150 = 0.07
"""Paper §4: maximum distance of a curve's parameter midpoint from its chord for a 150 mm sheet, mm."""

MERGE_PER_150 = 0.05
"""Default merge tolerance for a 150 mm sheet, mm (the paper used Origami Simulator's 1.0 mm).

1.0 mm per 150 mm would collapse genuine segments of the dense fixtures. Shortest drawn segments measured in
``../shared/fixtures/origami-simulator``, scaled to a 150 mm sheet (sheet size as :func:`sheet_size`):
``shell14`` 0.063 mm (ruling rungs at the panel tips), ``huffmanTower`` 0.104 mm (facet fans), ``Carved_Cylinder``
0.83 mm, ``Treble_Clef`` 1.53 mm, ``CircularPleat-antiFacet`` 1.88 mm (border ring chords), ``miura-ori`` 10 mm.
Our own curve chords go down to ≈ sqrt(8·tolerance·radius) (0.3 mm on a 0.2 mm-radius bend at the default
tolerance). 0.05 mm per 150 mm is below every one of them (20 % margin on shell14) yet far above float noise,
so endpoints that designers snapped by eye in drawing programs (typically within 0.01 mm) are still welded.
"""

SNAP_FACTOR = 4.0
"""A computed crossing point within this many merge tolerances of an existing vertex is snapped to that vertex.

Drawn vertices are merged only at the merge tolerance (so short drawn segments survive), but crossing points are
derived: lines drawn "through" a junction miss it by a hair (``curvedPleatSimple``'s facet lines pass 0.1 px from
its centre) and would otherwise leave a cluster of sliver segments there.
"""

MAX_SEGMENTS = 200_000
"""Guard against explosion: discretisation parameters that would produce more segments than this are enlarged."""

TOLERANCE_FLOOR_OF_MERGE = 1e-4
"""Smallest curve tolerance, as a fraction of the merge tolerance (or of a millionth of the sheet when merging is
off). A chord of length c on a curve of radius R deviates c²/(8R) from it, so at this tolerance every chord on a
curve tighter than 1,250 merge tolerances is shorter than the merge tolerance and would be welded again: asking
for less only costs time (``--tolerance 1e-12`` ran for minutes). Fine tolerances such as 1e-5 mm on a 100 mm
sheet (merge 0.033 mm) stay allowed."""

MIN_SHEET_MM = 1e-3
"""Smallest sheet extent accepted (1 µm): below it the merge tolerance and the solver's scale lose all meaning."""

MAX_COORDINATE_MM = 1e8
"""Largest |coordinate| accepted (100 km): beyond it squared lengths and cross products overflow or lose precision;
such values come from a wrong unit or viewBox, never from a real sheet."""

JUNCTION_SLIVER_FRACTION = 0.25
"""A curve sample vertex closer than this many ``interval`` to a junction on its curve is removed when the curve
allows (see :func:`_drop_samples_beside_junctions`)."""

SHORT_OF_BORDER_FRACTION = 0.01
"""A crease or cut whose free end lies within this fraction of the sheet size of the border is moved onto it (with a
warning when the gap is beyond the merge tolerance): drawn by hand or eye, "to the edge" often stops a few tenths of
a millimetre short, and a crease that does not reach the border cannot fold its last piece fully (a hand-drawn
160 mm sheet: ends 0.2 and 0.3 mm short folded 9° and 13° of 110° there, silently), nor at all when it stops short
at both ends (the verdict's crease that ends inside the paper). An end farther inside is the designer's."""

PRIORITY = {"B": 0, "C": 1, "M": 2, "V": 2, "U": 3, "F": 4}
"""Which assignment wins when two drawn segments coincide: the sheet outline first (a crease on the border cannot
fold: it has one face), then cuts, creases with a target, undriven hinges, and facet lines last."""


def default_parameters(size_mm: float) -> tuple[float, float, float]:
    """Paper defaults scaled to the sheet: ``(interval, tolerance, merge_tolerance)`` in mm."""
    if not (size_mm > 0 and math.isfinite(size_mm)):
        raise PatternError(f"crease pattern: sheet size {size_mm!r} mm is not a positive number")
    k = size_mm / REFERENCE_SIZE_MM
    return INTERVAL_PER_150 * k, TOLERANCE_PER_150 * k, MERGE_PER_150 * k


# ---------------------------------------------------------------------------------------------------- curves


def _segment_length(seg: CurveSegment, samples: int = 256) -> float:
    if seg.kind == "line":
        return float(np.hypot(*(seg.points[1] - seg.points[0])))
    p = seg.evaluate(np.linspace(0.0, 1.0, samples + 1))
    return float(np.hypot(*np.diff(p, axis=0).T).sum())


def _estimate_pieces(seg: CurveSegment, interval: float, tolerance: float) -> float:
    """Rough number of chords a curved segment needs: max(length/interval, ∫ sqrt(κ / 8·tol) ds)."""
    p = seg.evaluate(np.linspace(0.0, 1.0, 257))
    d = np.diff(p, axis=0)
    ds = np.hypot(d[:, 0], d[:, 1])
    length = float(ds.sum())
    # libm's atan2, not numpy's (whose last bit depends on the numpy version and CPU), so the estimate is the same
    ang = np.fromiter(map(math.atan2, d[:, 1].tolist(), d[:, 0].tolist()), dtype=float, count=len(d))
    turn = np.abs((np.diff(ang) + np.pi) % (2 * np.pi) - np.pi)
    local = 0.5 * (ds[1:] + ds[:-1])
    by_tol = float(np.sqrt(turn * local / (8.0 * tolerance)).sum())
    return max(length / interval, by_tol, 1.0)


CUSP_SPEED = 0.02
"""An interior point of a cubic where its speed |B′(t)| falls under this fraction of its fastest is a cusp (the
handles crossed: the curve stops and turns back) or nearly one (handles 1–2 mm short of crossing on a 150 mm sheet:
0.0015–0.003; a small loop 0.007), and a vertex of its polyline (:func:`_cusp_parameters`). The drawings we have
without one have 0.09 or more."""


def _cusp_parameters(seg: CurveSegment) -> list[float]:
    """Interior parameters of ``seg``'s cusps (only a cubic has them): where its speed has a local minimum under
    :data:`CUSP_SPEED` of its fastest, found on 256 steps and polished by ternary search on |B′|²."""
    if seg.kind != "cubic":
        return []
    p = seg.points
    d0, d1, d2 = p[1] - p[0], p[2] - p[1], p[3] - p[2]

    def speed2(t: np.ndarray) -> np.ndarray:
        s = 1.0 - t[:, None]
        v = s * s * d0 + 2.0 * s * t[:, None] * d1 + t[:, None] * t[:, None] * d2
        return np.einsum("ij,ij->i", v, v)

    t = np.linspace(0.0, 1.0, 257)
    v = speed2(t)
    low = np.flatnonzero((v[1:-1] <= v[:-2]) & (v[1:-1] < v[2:]) & (v[1:-1] < CUSP_SPEED**2 * v.max())) + 1
    out = []
    for i in low.tolist():
        a, b = t[i - 1], t[i + 1]
        for _ in range(60):
            m1, m2 = a + (b - a) / 3.0, b - (b - a) / 3.0
            a, b = (a, m2) if speed2(np.array([m1]))[0] <= speed2(np.array([m2]))[0] else (m1, b)
        out.append(0.5 * (a + b))
    return out


@dataclass(frozen=True)
class _Part:
    """The part ``lo``–``hi`` of a cubic's parameter range as a segment of its own (parameter ``u`` 0–1), the side
    of a cusp: ``t = lo + (hi − lo)·√u`` from a cusp at ``lo`` (``hi − (hi − lo)·√(1 − u)`` to one at ``hi``), since
    the curve leaves a cusp as (t − c)²: equal steps of ``u`` are then about equal steps along it, where equal steps
    of ``t`` crowded the cusp with 0.14 mm chords."""

    seg: CurveSegment
    lo: float
    hi: float
    cusp_at_lo: bool
    kind: str = "part"  # a curve piece without cusps inside: not split again

    def parameter(self, u: np.ndarray) -> np.ndarray:
        u = np.asarray(u, dtype=float)
        if self.cusp_at_lo:
            return self.lo + (self.hi - self.lo) * np.sqrt(u)
        return self.hi - (self.hi - self.lo) * np.sqrt(1.0 - u)

    def evaluate(self, u: np.ndarray | float) -> np.ndarray:
        return self.seg.evaluate(self.parameter(np.asarray(u, dtype=float)))


def curve_parameters(
    seg: CurveSegment,
    interval: float,
    tolerance: float,
    budget: int = MAX_SEGMENTS,
    cusps: list[float] | None = None,
) -> np.ndarray:
    """Parameters of the polyline vertices of one curved segment (paper §3.1), sorted, starting 0 and ending 1.

    Equal parameter steps with the smallest count whose chords are all ≤ ``interval``, then repeated insertion of
    the parameter midpoint of every chord whose curve midpoint is farther than ``tolerance`` from it. Stops early
    (returning what it has) if the count would exceed ``budget``. A cubic's cusps are vertices, each side sampled
    on its own: a chord across a cusp strays from the curve in proportion to its length, so halving it never met
    the tolerance, and the curve was sampled down to the merge tolerance there (a designer session's cusp: the
    warning asked for a larger tolerance, which changed nothing, and 82 mm triangles fanned onto the 1 mm stretch).
    ``cusps``: :func:`_cusp_parameters` of ``seg``, if the caller has them already.
    """
    if cusps is None:
        cusps = _cusp_parameters(seg)
    if cusps:
        # each part with one cusp end: between two cusps (a tiny loop), split at the middle; its parameters from
        # equal steps along it, then refined below on the segment's own parameter, as any curve's are
        sides = [(0.0, cusps[0], False)]
        for a, b in zip(cusps[:-1], cusps[1:], strict=True):
            sides += [(a, 0.5 * (a + b), True), (0.5 * (a + b), b, False)]
        sides.append((cusps[-1], 1.0, True))
        parts = []
        for lo, hi, at_lo in sides:
            part = _Part(seg, lo, hi, cusp_at_lo=at_lo)
            parts.append(part.parameter(_equal_steps(part, interval, budget)[:-1]))  # type: ignore[arg-type]
        t = np.concatenate([*parts, [1.0]])
    else:
        t = _equal_steps(seg, interval, budget)
    p = seg.evaluate(t)
    at_cusp = np.array(cusps)
    for _ in range(64):
        tm = 0.5 * (t[:-1] + t[1:])
        bad = _strays(seg, t, p, tolerance)
        if not bad.any() or len(t) + int(bad.sum()) > budget + 1:
            break
        # a chord is split at its parameter midpoint, or from a cusp at 1/√2 of its parameter span: the curve
        # leaves a cusp as (t − c)², so that is its midpoint along the curve (the parameter's fell at a quarter)
        start, end = t[:-1], t[1:]
        step = (end - start) * math.sqrt(0.5)
        ti = np.where(np.isin(start, at_cusp), start + step, np.where(np.isin(end, at_cusp), end - step, tm))
        order = np.argsort(np.concatenate([t, ti[bad]]), kind="stable")
        t = np.concatenate([t, ti[bad]])[order]
        p = np.concatenate([p, seg.evaluate(ti[bad])])[order]
    return t


STRAY_PROBES = (0.25, 0.5, 0.75)
"""Where along each chord's parameter span the curve's distance from the chord is measured. At the middle alone, a
chord across an inflection looked exact: a symmetric S-curve passes through its chord's midpoint, and a lamp-shade
strip's S-shaped creases (2.3 mm from their chords, the tolerance 0.47 mm) were each kept as one straight chord,
so the strip folded as a flat zigzag (a designer session)."""


def _strays(seg: CurveSegment, t: np.ndarray, p: np.ndarray, tolerance: float) -> np.ndarray:
    """Which chords ``p[k] → p[k+1]`` (the curve at ``t``) the curve strays from by more than ``tolerance`` at any of
    :data:`STRAY_PROBES`."""
    span = np.diff(t)
    bad = np.zeros(len(span), dtype=bool)
    for f in STRAY_PROBES:
        bad |= point_segment_distance(seg.evaluate(t[:-1] + f * span), p[:-1], p[1:]) > tolerance
    return bad


def _equal_steps(seg: CurveSegment, interval: float, budget: int) -> np.ndarray:
    """Equal parameter steps, the fewest whose chords are all ≤ ``interval`` (at most ``budget``)."""
    length = _segment_length(seg)
    n = max(1, math.ceil(length / interval))
    tries = 0
    while True:
        t = np.linspace(0.0, 1.0, n + 1)
        longest = float(np.hypot(*np.diff(seg.evaluate(t), axis=0).T).max())
        if longest <= interval * (1 + 1e-12) or n >= budget:
            return t
        tries += 1
        n = n + 1 if tries < 64 else math.ceil(n * 1.25)


def _segment_polyline(
    seg: CurveSegment, interval: float, tolerance: float, budget: int, cusps: list[float]
) -> tuple[np.ndarray, bool, float]:
    """Polyline points of one drawn segment, whether they discretise a curve (see module docstring), and the
    largest distance of a chord's curve midpoint from the chord (0 for straight segments): above ``tolerance``
    when refinement stopped at the budget. ``cusps``: its :func:`_cusp_parameters`."""
    start, end = seg.points[0], seg.points[-1]
    if seg.is_straight:
        # Straight border segments are subdivided after the planar clean-up (see _subdivide_straight), so their
        # pieces are spread evenly between the junctions the designer drew and never leave slivers next to them.
        return np.array([start, end], dtype=float), False, 0.0
    t = curve_parameters(seg, interval, tolerance, budget, cusps)
    pts = seg.evaluate(t)
    pts[0], pts[-1] = start, end  # exact joints with the neighbouring segments
    worst = float(point_segment_distance(seg.evaluate(0.5 * (t[:-1] + t[1:])), pts[:-1], pts[1:]).max())
    return pts, True, worst


# ---------------------------------------------------------------------------------------------------- arrangement


def _merge_points(pts: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Merge points closer than ``tol`` into the first representative (input order), as Origami Simulator does.

    Returns ``(representative_points, index)`` with ``pts[i] ≈ representative_points[index[i]]``. Exact duplicates
    go through :func:`numpy.unique`; near pairs come from a hash grid of cell ``tol`` (3×3 neighbourhood).
    """
    if len(pts) == 0:
        return pts.reshape(0, 2), np.zeros(0, dtype=np.int64)
    uniq, first, inv = np.unique(pts, axis=0, return_index=True, return_inverse=True)
    inv = inv.reshape(-1)
    order = np.argsort(first, kind="stable")  # unique points in order of first appearance
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    u = uniq[order]
    inv = rank[inv]
    k = len(u)
    rep = np.arange(k)
    if tol > 0 and k > 1:
        cell = np.floor((u - u.min(axis=0)) / tol).astype(np.int64)
        width = int(cell[:, 1].max()) + 3
        code = cell[:, 0] * width + cell[:, 1]
        srt = np.argsort(code, kind="stable")
        code_s = code[srt]
        pairs_i, pairs_j = [], []
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                target = code + dx * width + dy
                lo = np.searchsorted(code_s, target, "left")
                hi = np.searchsorted(code_s, target, "right")
                cnt = hi - lo
                if not cnt.any():
                    continue
                i = np.repeat(np.arange(k), cnt)
                offs = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
                j = srt[np.repeat(lo, cnt) + offs]
                keep = j > i
                pairs_i.append(i[keep])
                pairs_j.append(j[keep])
        pi = np.concatenate(pairs_i) if pairs_i else np.zeros(0, np.int64)
        pj = np.concatenate(pairs_j) if pairs_j else np.zeros(0, np.int64)
        close = np.hypot(*(u[pi] - u[pj]).T) < tol
        pi, pj = pi[close], pj[close]
        if len(pi):
            o = np.lexsort((pi, pj))
            # Greedy in input order: j joins the first earlier point that is still its own representative.
            for i, j in zip(pi[o].tolist(), pj[o].tolist(), strict=True):
                if rep[j] == j and rep[i] == i:
                    rep[j] = i
    keep_idx = np.flatnonzero(rep == np.arange(k))
    new_index = np.full(k, -1, dtype=np.int64)
    new_index[keep_idx] = np.arange(len(keep_idx))
    return u[keep_idx], new_index[rep][inv]


def _nearest_within(verts: np.ndarray, pts: np.ndarray, radius: float) -> np.ndarray:
    """Index of the nearest vertex within ``radius`` of each point, or -1 (hash grid of cell ``radius``)."""
    out = np.full(len(pts), -1, dtype=np.int64)
    if radius <= 0 or len(pts) == 0 or len(verts) == 0:
        return out
    origin = np.minimum(verts.min(axis=0), pts.min(axis=0))
    vc = np.floor((verts - origin) / radius).astype(np.int64)
    pc = np.floor((pts - origin) / radius).astype(np.int64)
    width = int(max(vc[:, 1].max(), pc[:, 1].max())) + 3
    vcode = vc[:, 0] * width + vc[:, 1]
    srt = np.argsort(vcode, kind="stable")
    vcode_s = vcode[srt]
    best = np.full(len(pts), np.inf)
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            target = (pc[:, 0] + dx) * width + pc[:, 1] + dy
            lo = np.searchsorted(vcode_s, target, "left")
            hi = np.searchsorted(vcode_s, target, "right")
            cnt = hi - lo
            if not cnt.any():
                continue
            pi = np.repeat(np.arange(len(pts)), cnt)
            vi = srt[np.repeat(lo, cnt) + np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)]
            dist = np.hypot(*(verts[vi] - pts[pi]).T)
            ok = dist < radius
            for p_, v_, d_ in zip(pi[ok].tolist(), vi[ok].tolist(), dist[ok].tolist(), strict=True):
                if d_ < best[p_]:
                    best[p_], out[p_] = d_, v_
    return out


def _candidate_pairs(a: np.ndarray, b: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (i < j) of segments whose tol-expanded bounding boxes overlap, via a uniform grid.

    The cell is at least twice the median segment and twice ``tol``, so a box spans a few cells: with points
    (segments of no length) close together, 1/2048 of their extent made every box 2,048² cells, and an outline drawn
    as one open stroke back to its start spent a second here on its two ends."""
    m = len(a)
    if m < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    lo = np.minimum(a, b) - tol
    hi = np.maximum(a, b) + tol
    origin = lo.min(axis=0)
    lengths = np.hypot(*(b - a).T)
    extent = float(np.max(hi.max(axis=0) - origin))
    h = max(2.0 * float(np.median(lengths)), 2.0 * float(tol), extent / 2048.0, 1e-9)
    while True:
        c0 = np.floor((lo - origin) / h).astype(np.int64)
        c1 = np.floor((hi - origin) / h).astype(np.int64)
        nx = c1[:, 0] - c0[:, 0] + 1
        ny = c1[:, 1] - c0[:, 1] + 1
        cnt = nx * ny
        if cnt.sum() <= 4_000_000:
            break
        h *= 2.0
    seg = np.repeat(np.arange(m), cnt)
    local = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    cx = c0[seg, 0] + local // ny[seg]
    cy = c0[seg, 1] + local % ny[seg]
    width = int(c1[:, 1].max()) + 2
    code = cx * width + cy
    order = np.lexsort((seg, code))
    code, seg = code[order], seg[order]
    # Groups of equal cell code; every entry pairs with the later entries of its group.
    starts = np.flatnonzero(np.r_[True, code[1:] != code[:-1]])
    sizes = np.diff(np.r_[starts, len(code)])
    group_end = np.repeat(starts + sizes, sizes)
    pos = np.arange(len(code))
    partners = group_end - pos - 1
    total = int(partners.sum())
    if total == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    src = np.repeat(pos, partners)
    off = np.arange(total) - np.repeat(np.cumsum(partners) - partners, partners)
    i, j = seg[src], seg[src + 1 + off]
    i, j = np.minimum(i, j), np.maximum(i, j)
    keep = i != j
    key = np.unique(i[keep] * m + j[keep])
    i, j = key // m, key % m
    overlap = np.all(lo[i] <= hi[j], axis=1) & np.all(lo[j] <= hi[i], axis=1)
    return i[overlap], j[overlap]


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _split_records(
    verts: np.ndarray, edges: np.ndarray, tol: float, fixed: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Where segments must be split: ``(edge, distance along it, vertex id or -1-k for new point k, new points)``.

    X crossings get one new point shared by both segments; T-junctions (an endpoint within ``tol`` of another
    segment's interior) and collinear overlaps split at the existing endpoint. ``fixed`` (bool per edge): segments
    that must not move (the border): a crossing on one snaps only to a vertex within ``tol`` of its line.
    """
    a, b = verts[edges[:, 0]], verts[edges[:, 1]]
    i, j = _candidate_pairs(a, b, tol)
    shared = (
        (edges[i, 0] == edges[j, 0])
        | (edges[i, 0] == edges[j, 1])
        | (edges[i, 1] == edges[j, 0])
        | (edges[i, 1] == edges[j, 1])
    )
    rec_e, rec_d, rec_v = [], [], []
    new_pts: list[np.ndarray] = []
    n_new = 0
    p, r = a[i], b[i] - a[i]
    q, s = a[j], b[j] - a[j]
    la, lb = np.hypot(*r.T), np.hypot(*s.T)
    rxs = _cross(r, s)
    qp = q - p
    parallel = np.abs(rxs) <= 1e-10 * la * lb
    # --- proper (non-parallel) intersections
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _cross(qp, s) / rxs
        u = _cross(qp, r) / rxs
    da, db = t * la, u * lb
    hit = ~parallel & (da >= -tol) & (da <= la + tol) & (db >= -tol) & (db <= lb + tol)
    # X crossings: inside both segments, away from every endpoint (a shared endpoint is not a crossing).
    in_a = hit & (da > tol) & (da < la - tol) & ~shared
    in_b = hit & (db > tol) & (db < lb - tol) & ~shared
    with np.errstate(invalid="ignore"):
        x = p + t[:, None] * r
    # A proper crossing within tol of an end of each segment passes the X test for neither and the T test below for
    # neither end (each projects within tol of the other segment's end), yet those ends are at least tol apart (or
    # they would have been merged): (1,0)–(0.001,0.002) crossed (0,0)–(0.002,0.002) for good. It is an X crossing
    # next to an existing vertex (one of those ends, or a vertex nearer still), so it snaps to it as below: the
    # segment that does not end there is split there.
    with np.errstate(invalid="ignore"):
        corner = hit & ~in_a & ~in_b & ~shared & (t > 0) & (t < 1) & (u > 0) & (u < 1)
    both = (in_a & in_b) | corner
    k = int(both.sum())
    if k:
        # A computed crossing next to an existing vertex (lines drawn "through" a junction that miss it by a
        # hair) snaps to that vertex instead of making a cluster of new ones: within SNAP_FACTOR × tol.
        xb = x[both]
        snap = _nearest_within(verts, xb, SNAP_FACTOR * tol)
        if fixed is not None:
            # the outline never moves: a crease drawn a little past the border crosses it next to its own end
            # point, outside the sheet; snapping the crossing there bent the border through that point
            for e in (i[both], j[both]):
                check = np.flatnonzero(snap >= 0)
                snap[check[_bends_outline(verts, edges, fixed, e[check], snap[check], tol)]] = -1
        fresh = snap < 0
        ids = snap.copy()
        ids[fresh] = -1 - (n_new + np.arange(int(fresh.sum())))
        n_new += int(fresh.sum())
        new_pts.append(xb[fresh])
        ib, jb = i[both], j[both]
        d_i = np.where(fresh, da[both], np.einsum("ij,ij->i", verts[np.maximum(snap, 0)] - p[both], r[both]) / la[both])
        d_j = np.where(fresh, db[both], np.einsum("ij,ij->i", verts[np.maximum(snap, 0)] - q[both], s[both]) / lb[both])
        # never split a segment at one of its own endpoints
        own_i = (snap == edges[ib, 0]) | (snap == edges[ib, 1])
        own_j = (snap == edges[jb, 0]) | (snap == edges[jb, 1])
        rec_e += [ib[~own_i], jb[~own_j]]
        rec_d += [d_i[~own_i], d_j[~own_j]]
        rec_v += [ids[~own_i], ids[~own_j]]
    # A crossing inside one segment but within tol of an end of the other: that end splits the first segment at the
    # crossing, as a T-junction would (the T test below projects the end, and (0,0)–(1,1) crossed by
    # (1,0)–(0,0.001), whose end lies a merge tolerance from (0,0), projects within tol of that end and was missed:
    # the two crossed for good)
    for near_end, seg_idx, other_idx, dist_in, dist_other, length_other in (
        (in_a & ~in_b, i, j, da, db, lb),
        (in_b & ~in_a, j, i, db, da, la),
    ):
        end_v = np.where(dist_other <= 0.5 * length_other, edges[other_idx, 0], edges[other_idx, 1])[near_end]
        seg_e, seg_d = seg_idx[near_end], dist_in[near_end]
        if fixed is not None:  # the outline never moves
            ok = ~_bends_outline(verts, edges, fixed, seg_e, end_v, tol)
            seg_e, seg_d, end_v = seg_e[ok], seg_d[ok], end_v[ok]
        rec_e.append(seg_e)
        rec_d.append(seg_d)
        rec_v.append(end_v)
    # T-junctions (and collinear overlaps): an endpoint of one segment within tol of the other's interior splits
    # the other at that endpoint. Checked directly, not through the line intersection, so nearly parallel
    # segments are caught too.
    for seg_idx, other_idx, base, dirv, length in ((i, j, p, r, la), (j, i, q, s, lb)):
        safe = np.maximum(length, 1e-300)
        for end in (0, 1):
            v = edges[other_idx, end]
            rel = verts[v] - base
            d = np.einsum("ij,ij->i", rel, dirv) / safe
            off = np.abs(_cross(dirv, rel)) / safe
            own = (v == edges[seg_idx, 0]) | (v == edges[seg_idx, 1])
            inside = (d > tol) & (d < length - tol) & (off <= tol) & ~own
            rec_e.append(seg_idx[inside])
            rec_d.append(d[inside])
            rec_v.append(v[inside])
    if not rec_e:
        z = np.zeros(0, np.int64)
        return z, np.zeros(0), z, np.zeros((0, 2))
    return (
        np.concatenate(rec_e).astype(np.int64),
        np.concatenate(rec_d),
        np.concatenate(rec_v).astype(np.int64),
        np.concatenate(new_pts) if new_pts else np.zeros((0, 2)),
    )


def _bends_outline(
    verts: np.ndarray, edges: np.ndarray, fixed: np.ndarray, e: np.ndarray, v: np.ndarray, tol: float
) -> np.ndarray:
    """Whether splitting edge ``e[k]`` at vertex ``v[k]`` would bend the outline: the edge is ``fixed`` (a border
    piece) and the vertex lies farther than ``tol`` from its line."""
    a, b = verts[edges[e, 0]], verts[edges[e, 1]]
    off = np.abs(_cross(b - a, verts[v] - a)) / np.maximum(np.hypot(*(b - a).T), 1e-300)
    return fixed[e] & (off > tol)


def _one_split_per_place(
    verts: np.ndarray, edges: np.ndarray, rec_e: np.ndarray, rec_d: np.ndarray, rec_v: np.ndarray, tol: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Of split points that fall within ``tol`` of each other along one edge, keep the one nearest the edge's line.

    Both ends of a segment no longer than ``tol`` can lie within ``tol`` of another segment; splitting that segment
    at both, at (nearly) the same distance along it, leaves their order to round-off and can make the pieces cross
    their neighbours. One split per place is what the drawing means.
    """
    if len(rec_e) < 2:
        return rec_e, rec_d, rec_v
    order = np.lexsort((rec_d, rec_e))
    rec_e, rec_d, rec_v = rec_e[order], rec_d[order], rec_v[order]
    a, b = verts[edges[rec_e, 0]], verts[edges[rec_e, 1]]
    r = b - a
    off = np.abs(_cross(r, verts[rec_v] - a)) / np.maximum(np.hypot(*r.T), 1e-300)
    new_place = np.ones(len(rec_e), dtype=bool)
    new_place[1:] = (rec_e[1:] != rec_e[:-1]) | (rec_d[1:] - rec_d[:-1] >= tol)
    place = np.cumsum(new_place)
    best = np.lexsort((off, place))
    keep = best[np.r_[True, place[best][1:] != place[best][:-1]]]
    return rec_e[keep], rec_d[keep], rec_v[keep]


def _apply_splits(
    verts: np.ndarray, edges: np.ndarray, rec: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray], tol: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split edges at the records; returns (vertices, new edges, index of the original edge for each new edge)."""
    rec_e, rec_d, rec_v, new_pts = rec
    n = len(verts)
    verts = np.concatenate([verts, new_pts]) if len(new_pts) else verts
    rec_v = np.where(rec_v < 0, n + (-1 - rec_v), rec_v)
    rec_e, rec_d, rec_v = _one_split_per_place(verts, edges, rec_e, rec_d, rec_v, tol)
    m = len(edges)
    stop_e = np.concatenate([np.arange(m), rec_e, np.arange(m)])
    stop_d = np.concatenate([np.full(m, -np.inf), rec_d, np.full(m, np.inf)])
    stop_v = np.concatenate([edges[:, 0], rec_v, edges[:, 1]])
    order = np.lexsort((stop_d, stop_e))
    stop_e, stop_v = stop_e[order], stop_v[order]
    same = stop_e[1:] == stop_e[:-1]
    new_edges = np.column_stack([stop_v[:-1][same], stop_v[1:][same]])
    return verts, new_edges, stop_e[:-1][same]


def _lone_slits(edges: np.ndarray, assignments: np.ndarray) -> np.ndarray:
    """Mask of the cut edges (C) whose two ends are both the tips of a slit: on no border edge and on no other cut.
    Cut open (``..mesh.triangulate.split_cuts``), a vertex gets a copy only where cuts or the border part its fan,
    so such a slit drawn as one segment stayed shut (a review session's kirigami lattice of 15 mm slits: 600 mm of
    mesh boundary where the border and both sides of every slit make 3,330 mm). In two pieces its middle vertex opens
    it."""
    n = int(edges.max()) + 1 if len(edges) else 0
    cut = assignments == "C"
    cuts_at = np.bincount(edges[cut].ravel(), minlength=n)
    on_border = np.zeros(n, dtype=bool)
    on_border[edges[assignments == "B"].ravel()] = True
    tip = (cuts_at == 1) & ~on_border
    return cut & tip[edges[:, 0]] & tip[edges[:, 1]]


def _subdivide_straight(
    verts: np.ndarray,
    edges: np.ndarray,
    attrs: np.ndarray,
    which: np.ndarray,
    interval: float,
    least: np.ndarray | int = 1,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split the straight edges ``which`` (bool mask) into ⌈length / interval⌉ equal pieces, ``least`` at least (per
    edge or for all) (paper §3.1: the border's, and a cut's, two border sides once cut; :mod:`..mesh.needles`:
    creases beside needles)."""
    a, b = verts[edges[:, 0]], verts[edges[:, 1]]
    length = np.hypot(*(b - a).T)
    n = np.where(which, np.maximum(least, np.ceil(length / interval - 1e-9)).astype(np.int64), 1)
    if np.all(n == 1):
        return verts, edges, attrs
    # new interior points: for edge k, parameters 1/n .. (n-1)/n
    k_new = np.repeat(np.arange(len(edges)), n - 1)
    step = np.arange(len(k_new)) - np.repeat(np.cumsum(n - 1) - (n - 1), n - 1) + 1
    s = (step / n[k_new])[:, None]
    new_pts = (1.0 - s) * a[k_new] + s * b[k_new]
    new_ids = len(verts) + np.arange(len(k_new))
    # chain of vertex ids per edge: start, interior..., end
    starts = np.cumsum(n + 1) - (n + 1)
    chain = np.empty(int((n + 1).sum()), dtype=np.int64)
    chain[starts] = edges[:, 0]
    chain[starts + n] = edges[:, 1]
    interior = np.ones(len(chain), bool)
    interior[starts] = False
    interior[starts + n] = False
    chain[interior] = new_ids
    owner = np.repeat(np.arange(len(edges)), n + 1)
    same = owner[1:] == owner[:-1]
    new_edges = np.column_stack([chain[:-1][same], chain[1:][same]])
    return np.concatenate([verts, new_pts]), new_edges, attrs[owner[:-1][same]]


def pattern_sheet_size(pattern: CreasePattern) -> float:
    """The sheet size of a discretised pattern, as :func:`sheet_size` is a drawing's: the largest extent of its
    border's vertices, or of every vertex if there is no border (0 for none)."""
    border = pattern.edges[pattern.assignments == "B"]
    pts = pattern.vertices[np.unique(border)] if len(border) else pattern.vertices
    return float(np.max(np.ptp(pts, axis=0))) if len(pts) else 0.0


def segment_parameters(
    pattern: CreasePattern, interval: float | None, tolerance: float | None
) -> tuple[float | None, float | None, list[str]]:
    """The interval and tolerance asked for a pattern read as segments (another tool's FOLD file), validated as a
    drawing's are (:func:`_resolve_parameters`): ``None`` stays ``None`` (the paper's, scaled to the sheet); an
    interval under the sheet's merge tolerance is raised to it, and one that would split the border into more than
    :data:`MAX_SEGMENTS` pieces is raised until it does not, each with a warning."""
    warnings: list[str] = []
    _check_positive(interval, tolerance)
    size = pattern_sheet_size(pattern)
    if interval is None or not (size > 0 and math.isfinite(size)):
        return interval, tolerance, warnings
    interval = _interval_above_merge(interval, default_parameters(size)[2], warnings)
    border = pattern.edges[pattern.assignments == "B"]
    length = float(np.hypot(*(pattern.vertices[border[:, 1]] - pattern.vertices[border[:, 0]]).T).sum())
    room = MAX_SEGMENTS - pattern.n_edges
    if length / interval > room > 0:
        used = length / room
        warnings.append(
            f"discretisation capped: interval {interval:g} mm would split the border into more than "
            f"{MAX_SEGMENTS} segments; used {used:.4g} mm"
        )
        interval = used
    return interval, tolerance, warnings


def with_thinned_polylines(
    pattern: CreasePattern, interval: float | None = None, tolerance: float | None = None
) -> CreasePattern:
    """``pattern`` with its chains of segments sampled far finer than the interval thinned to the paper's sampling,
    as a drawing's dense polylines are (:func:`.polylines.thin_dense_polylines`: chords up to ``interval`` that keep
    every skipped vertex within ``tolerance``; ends, junctions and changes of role or angle stay; facet lines are
    kept as drawn), for crease patterns read as straight segments: a FOLD file from another tool stores a curve as
    a polyline of its own sampling, and kept point for point, 200 points to a 50 mm curve fanned 20 mm triangles
    onto 0.5 mm pieces (495 corners under 1° where its SVG twin has none; a 1 m CAD sheet: 10,052 faces, 6.7 s,
    against 202 faces). ``interval`` and ``tolerance`` default to the paper's, scaled to the sheet. A chord keeps
    the source of the first segment it replaces, so messages name the file's edge where it starts."""
    size = pattern_sheet_size(pattern)
    if not (size > 0 and math.isfinite(size)):
        return pattern
    d_interval, d_tolerance, _ = default_parameters(size)
    interval = d_interval if interval is None else interval
    tolerance = d_tolerance if tolerance is None else tolerance
    kept, chords, source = thin_dense_polylines(
        pattern.vertices,
        pattern.edges,
        pattern.assignments,
        pattern.fold_angles,
        pattern.assignments != "F",
        interval,
        tolerance,
    )
    if len(chords) == 0:
        return pattern
    attrs = np.concatenate([np.flatnonzero(kept), source])
    edges = np.concatenate([pattern.edges[kept], chords])
    used = np.unique(edges)
    remap = np.full(pattern.n_vertices, -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return _with_edges(pattern, pattern.vertices[used], remap[edges], attrs)


def _with_edges(pattern: CreasePattern, vertices: np.ndarray, edges: np.ndarray, attrs: np.ndarray) -> CreasePattern:
    """``pattern`` with new ``vertices`` and ``edges``, edge k taking the role, angle, source and curve flag of
    ``pattern``'s edge ``attrs[k]``."""
    return replace(
        pattern,
        vertices=vertices,
        edges=edges,
        assignments=pattern.assignments[attrs],
        fold_angles=pattern.fold_angles[attrs],
        edge_polyline=pattern.edge_polyline[attrs],
        edge_from_curve=pattern.edge_from_curve[attrs],
    )


def with_flattened_curves(pattern: CreasePattern, tolerance: float | None = None) -> CreasePattern:
    """``pattern`` with the chains of its segments that follow a curve marked as curve pieces
    (:func:`.polylines.flattened_curves`), for crease patterns read as straight segments (a FOLD file from another
    tool). ``tolerance`` defaults to the paper's, scaled to the sheet (:func:`default_parameters` of the largest
    extent of the border, or of every vertex if there is none)."""
    if tolerance is None:
        size = pattern_sheet_size(pattern)
        if not (size > 0 and math.isfinite(size)):
            return pattern
        tolerance = default_parameters(size)[1]
    curve = pattern.edge_from_curve | flattened_curves(
        pattern.vertices, pattern.edges, pattern.assignments, pattern.fold_angles, tolerance
    )
    return pattern if np.array_equal(curve, pattern.edge_from_curve) else replace(pattern, edge_from_curve=curve)


def subdivide_straight_border(pattern: CreasePattern, interval: float | None = None) -> CreasePattern:
    """``pattern`` with its straight border edges split into ⌈length / interval⌉ equal pieces (paper §3.1, the step
    a drawn pattern gets in :func:`discretize`), for crease patterns read as straight segments: a FOLD file from
    another tool usually draws a rectangular sheet as four long edges, and without border vertices to attach
    rulings to, the triangulation fans slivers into the corners (a sine-pleat strip: smallest corner 0.06° instead
    of 8.2°, mean fold-angle error 14.9° instead of 2.2°). ``interval`` defaults to the paper's, scaled to the
    sheet (:func:`pattern_interval`). Edges already short enough are unchanged. Straight cuts are split alike, a
    lone slit into two at least (:func:`_lone_slits`)."""
    which = np.isin(pattern.assignments, ("B", "C")) & ~pattern.edge_from_curve
    least = np.where(_lone_slits(pattern.edges, pattern.assignments), 2, 1)
    return subdivide_edges(pattern, which, interval, least)


def with_crossings_split(pattern: CreasePattern) -> CreasePattern:
    """``pattern`` with its edges that cross or touch another away from a vertex split there, by the planar
    clean-up a drawing gets (:func:`_planar_arrangement`, :func:`_remove_duplicates`, at the sheet's merge
    tolerance), with a warning naming the first pair; for crease patterns read as segments (a FOLD file from
    another tool). The FOLD spec takes a crease pattern as a planar graph, but a hand-made or scripted file may
    draw two creases across each other as single edges, and was refused where its SVG twin folds (a designer
    session). A pattern without such edges is returned as it is."""
    size = pattern_sheet_size(pattern)
    if not (size > 0 and math.isfinite(size)) or pattern.n_edges == 0:
        return pattern
    tol = default_parameters(size)[2]
    rec = _split_records(pattern.vertices, pattern.edges, tol, pattern.assignments == "B")
    _, first, inverse = np.unique(np.sort(pattern.edges, axis=1), axis=0, return_index=True, return_inverse=True)
    again = np.flatnonzero(first[inverse.reshape(-1)] != np.arange(pattern.n_edges))  # edges listed a second time
    if len(rec[0]) == 0 and len(again) == 0:
        return pattern
    a, b = pattern.vertices[pattern.edges[:, 0]], pattern.vertices[pattern.edges[:, 1]]
    pieces = _Pieces(a, b, pattern.edge_polyline, pattern.edge_from_curve, pattern.assignments, pattern.fold_angles)
    warnings: list[str] = []
    verts, edges, attrs = _planar_arrangement(pieces, tol, pattern.sources)
    edges, attrs = _remove_duplicates(edges, attrs, pieces, pattern.sources, warnings)
    out = _with_edges(pattern, verts, edges, attrs)
    if len(rec[0]) == 0:  # edges listed twice only: kept once, by role (the drawing's rule)
        k0, k1 = int(first[inverse.reshape(-1)[again[0]]]), int(again[0])
        named = " and ".join(dict.fromkeys(pattern.sources[k] for k in pattern.edge_polyline[[k0, k1]].tolist()))
        said = f"{len(again)} edge(s) listed twice (first {named}, between the same two vertices): kept once"
        out.warnings = [*pattern.warnings, said, *warnings]
        return out
    split = np.unique(rec[0])
    # the first place and the edges that meet there: both split at a crossing's new point, or one split at the
    # other's end (a T); not the two lowest-numbered edges split anywhere (a review session's warning named two
    # border edges that do not touch)
    e0, v0 = int(rec[0][0]), int(rec[2][0])
    if v0 < 0:
        where = rec[3][-1 - v0]
        pair = [e0, *[int(e) for e in rec[0][rec[2] == v0].tolist() if e != e0][:1]]
    else:
        where = pattern.vertices[v0]
        pair = [e0, *[int(e) for e in np.flatnonzero((pattern.edges == v0).any(axis=1)).tolist()][:1]]
    names = " and ".join(dict.fromkeys(pattern.sources[k] for k in pattern.edge_polyline[pair].tolist()))
    said = (
        f"{len(split)} edge(s) cross or touch other edges away from a vertex (first {names}, near "
        f"({where[0]:.4g}, {where[1]:.4g}) mm): split there, as a drawing's crossings are"
    )
    out.warnings = [*pattern.warnings, said, *warnings]
    return out


def segments_at_interval(
    pattern: CreasePattern, interval: float | None = None, tolerance: float | None = None
) -> CreasePattern:
    """A crease pattern read as straight segments (a FOLD file from another tool) sampled as a drawing is, at
    ``interval`` and ``tolerance`` (mm; ``None``: the paper's, scaled to the sheet): the values checked
    (:func:`segment_parameters`), its dense polylines thinned (:func:`with_thinned_polylines`), its straight
    border split (:func:`subdivide_straight_border`) and its chains that follow a curve marked as curve pieces
    (:func:`with_flattened_curves`). One function for every door: the command line's ``--interval`` and the Fold
    panel's Interval give the same pattern (a Blender import kept the automatic interval, whatever was set)."""
    interval, tolerance, said = segment_parameters(pattern, interval, tolerance)
    pattern = with_thinned_polylines(pattern, interval, tolerance)
    pattern = with_flattened_curves(subdivide_straight_border(pattern, interval), tolerance)
    if interval is not None:
        pattern = replace(pattern, interval=interval)
    pattern.warnings = [*pattern.warnings, *said]
    pattern.validate()
    return pattern


def pattern_interval(pattern: CreasePattern) -> float:
    """The interval ``pattern`` was discretised at, or for a pattern read as segments (``interval`` nan) the
    paper's, scaled to its sheet (:func:`default_parameters` of the border's largest extent)."""
    if not math.isnan(pattern.interval):
        return pattern.interval
    return default_parameters(pattern_sheet_size(pattern))[0]


def subdivide_edges(
    pattern: CreasePattern, which: np.ndarray, interval: float | None = None, least: np.ndarray | int = 1
) -> CreasePattern:
    """``pattern`` with the straight edges ``which`` (bool mask) split into ⌈length / interval⌉ equal pieces (``least``
    at least); edge k's first piece stays edge k (messages name a file's edges by index), the other pieces come
    after. ``interval`` defaults to :func:`pattern_interval`. Edges already short enough are unchanged."""
    if not which.any():
        return pattern
    if interval is None:
        interval = pattern_interval(pattern)
    if not (interval > 0 and math.isfinite(interval)):  # a sheet of one point, or an infinite interval: no split
        return pattern
    m = len(pattern.edges)
    verts, edges, attrs = _subdivide_straight(pattern.vertices, pattern.edges, np.arange(m), which, interval, least)
    if len(edges) == m:
        return pattern
    first = np.r_[True, attrs[1:] != attrs[:-1]]
    order = np.r_[np.flatnonzero(first), np.flatnonzero(~first)]
    return _with_edges(pattern, verts, edges[order], attrs[order])


def _drop_samples_beside_junctions(
    verts: np.ndarray, edges: np.ndarray, attrs: np.ndarray, pieces: _Pieces, interval: float, tolerance: float
) -> tuple[np.ndarray, np.ndarray, int]:
    """Remove curve sample vertices left a hair from a junction (issue 12: no sliver beyond what the creases force).

    A curve's sample points are placed before the crossings are known, so a crossing or T-junction can land a small
    fraction of a chord from one of them; the short piece between them makes corners of a few degrees down to
    fractions of a degree with every far vertex it is triangulated to. Such a sample vertex (two pieces of the same
    drawn curve, nothing else) is removed when its piece to the junction is shorter than
    :data:`JUNCTION_SLIVER_FRACTION` × ``interval`` and it lies within ``tolerance`` of the chord that replaces its two
    pieces (so the polyline stays as close to the curve as the paper asks, §3.1), and no other vertex lies in the
    thin triangle it leaves. Returns ``(edges, attrs, removed)``; the removed vertices are dropped as unused later.
    """
    n = len(verts)
    deg = np.bincount(edges.ravel(), minlength=n)
    curve = pieces.from_curve[attrs]
    length = np.hypot(*(verts[edges[:, 1]] - verts[edges[:, 0]]).T)
    d0, d1 = deg[edges[:, 0]], deg[edges[:, 1]]
    short = curve & (length < JUNCTION_SLIVER_FRACTION * interval) & ((d0 == 2) != (d1 == 2))
    if not short.any():
        return edges, attrs, 0
    samples = np.unique(np.where(d0[short] == 2, edges[short, 0], edges[short, 1]))
    inc: dict[int, list[int]] = {}
    for k in np.flatnonzero(np.isin(edges, samples).any(axis=1)).tolist():
        for v in edges[k].tolist():
            if deg[v] == 2:
                inc.setdefault(v, []).append(k)
    drop = np.zeros(len(edges), dtype=bool)
    new_edges = edges.copy()
    touched: set[int] = set()  # samples and far ends of removals made: not moved again
    sectors: dict[int, list[tuple[int, np.ndarray, np.ndarray]]] = {}  # per junction, its removals' curve and sector
    removed = 0
    for k in np.flatnonzero(short).tolist():
        a, b = edges[k].tolist()
        for junction, sample in ((a, b), (b, a)):
            if deg[junction] == 2 or deg[sample] != 2 or sample in touched or junction in touched - sectors.keys():
                continue
            k2 = next(x for x in inc[sample] if x != k)
            w = int(edges[k2, 0] if edges[k2, 1] == sample else edges[k2, 1])
            same = (
                curve[k2]
                and pieces.polyline[attrs[k2]] == pieces.polyline[attrs[k]]
                and pieces.assignment[attrs[k2]] == pieces.assignment[attrs[k]]
            )
            if not same or w == junction or w in touched:
                continue
            pa, pb, pw = verts[junction], verts[sample], verts[w]
            if point_segment_distance(pb[None], pa[None], pw[None])[0] > tolerance:
                continue
            if np.any(np.all(np.sort(edges[~drop], axis=1) == sorted((junction, w)), axis=1)):
                continue  # the chord exists already
            # no other vertex in the triangle (junction, sample, w) the removal sweeps over
            o1 = _cross((pb - pa)[None], verts - pa)
            o2 = _cross((pw - pb)[None], verts - pb)
            o3 = _cross((pa - pw)[None], verts - pw)
            inside = ((o1 > 0) & (o2 > 0) & (o3 > 0)) | ((o1 < 0) & (o2 < 0) & (o3 < 0))
            inside[[junction, sample, w]] = False
            if inside.any():
                continue
            # another curve through the junction (a crease crossing a curved border: the border's sample beside
            # the crossing went first, and a designer's 0.07 mm stub of the crease stayed): one sample per drawn
            # curve (both of a circle's beside a ray's end made its arc coarser there: rays on a 20 mm circle missed
            # their angles by 9° more), its triangle clear of any swept from the junction already
            line = int(pieces.polyline[attrs[k]])
            if any(ln == line or _sectors_overlap(pb - pa, pw - pa, u, v) for ln, u, v in sectors.get(junction, ())):
                continue
            new_edges[k] = (junction, w)
            drop[k2] = True
            touched.update((junction, sample, w))
            sectors.setdefault(junction, []).append((line, pb - pa, pw - pa))
            removed += 1
            break
    return new_edges[~drop], attrs[~drop], removed


def _sectors_overlap(p: np.ndarray, q: np.ndarray, u: np.ndarray, v: np.ndarray) -> bool:
    """Whether the angular sectors between the directions ``p``, ``q`` and between ``u``, ``v`` (each under 180°,
    from one vertex) share more than a boundary direction (two equal sectors would be two curves on top of each
    other, which the planar clean-up has removed)."""

    def within(d: np.ndarray, a: np.ndarray, b: np.ndarray) -> bool:
        turn = float(_cross(a[None], b[None])[0])
        return turn * float(_cross(a[None], d[None])[0]) > 0 and turn * float(_cross(d[None], b[None])[0]) > 0

    return within(u, p, q) or within(v, p, q) or within(p, u, v) or within(q, u, v)


def _inside_border(points: np.ndarray, border_a: np.ndarray, border_b: np.ndarray) -> np.ndarray:
    """Even-odd test of points against the closed border polygon(s) given as segments (vectorised).

    The points are taken in horizontal bands, each against the border segments whose y-range meets the band (only
    those can straddle a point's height): the same counts as every point against every segment, which took 0.5 s
    for 27,800 crease pieces inside a border of 3,224 (a 1 m sheet drawn as 1 mm polylines)."""
    out = np.zeros(len(points), dtype=bool)
    if len(points) == 0 or len(border_a) == 0:
        return out
    ay, by = border_a[:, 1], border_b[:, 1]
    ax, bx = border_a[:, 0], border_b[:, 0]
    ylo, yhi = np.minimum(ay, by), np.maximum(ay, by)
    py_all = points[:, 1]
    bands = max(1, min(256, int(np.sqrt(len(border_a)))))
    cuts = np.quantile(py_all, np.linspace(0.0, 1.0, bands + 1))
    band = np.clip(np.searchsorted(cuts, py_all, side="right") - 1, 0, bands - 1)
    for k in range(bands):
        idx = np.flatnonzero(band == k)
        if len(idx) == 0:
            continue
        lo, hi = float(py_all[idx].min()), float(py_all[idx].max())
        seg = np.flatnonzero((yhi > lo) & (ylo <= hi))  # a straddling segment has ylo <= py < yhi
        if len(seg) == 0:
            continue
        chunk = max(1, 2_000_000 // len(seg))
        for s in range(0, len(idx), chunk):
            rows = idx[s : s + chunk]
            px, py = points[rows, 0:1], points[rows, 1:2]
            straddle = (ay[seg] > py) != (by[seg] > py)
            with np.errstate(divide="ignore", invalid="ignore"):
                xc = ax[seg] + (py - ay[seg]) * (bx[seg] - ax[seg]) / (by[seg] - ay[seg])
            out[rows] = (np.count_nonzero(straddle & (px < xc), axis=1) % 2) == 1
    return out


def _listed(texts: list[str], limit: int = 4) -> str:
    """The first ``limit`` of ``texts`` joined by commas, and how many more there are (a warning that counted 6
    crease ends listed 4 places and said nothing of the other 2)."""
    return ", ".join(texts[:limit]) + (f" and {len(texts) - limit} more" if len(texts) > limit else "")


def _describe_sources(sources: list[str], idx: np.ndarray, limit: int = 4) -> str:
    return _listed([sources[k] for k in dict.fromkeys(idx.tolist())], limit)


# ---------------------------------------------------------------------------------------------------- main


def sheet_size(curves: list[CreaseCurve]) -> float:
    """Largest extent (mm) of the border's bounding box, or of all curves' if there is no border."""
    chosen = [c for c in curves if c.assignment == "B"] or curves
    pts = [s.evaluate(np.linspace(0.0, 1.0, 33)) for c in chosen for s in c.segments]
    if not pts:
        raise PatternError("crease pattern: no segments to discretise")
    allp = np.concatenate(pts)
    return float(np.max(allp.max(axis=0) - allp.min(axis=0)))


@dataclass
class _Pieces:
    """Drawn segments as straight pieces ``a[i]→b[i]`` with their per-piece attributes (indexed by ``attrs`` later)."""

    a: np.ndarray
    b: np.ndarray
    polyline: np.ndarray  # index into ``sources`` (the drawn curve)
    from_curve: np.ndarray  # the piece discretises a curved segment
    assignment: np.ndarray
    fold_angle: np.ndarray


def _a(kind: str) -> str:
    """A segment kind with its article, for messages ("an arc", "a line")."""
    return ("an " if kind[:1] in "aeiou" else "a ") + kind


def _check_coordinates(curves: list[CreaseCurve]) -> None:
    """Reject non-finite and absurdly large coordinates (one clear line naming the curve).

    All points are checked in one array operation; only when one fails are the curves searched for the first
    culprit (a per-segment check cost ~80 ms on a 3,000-segment pattern, in one unit of a Blender job)."""
    points = [seg.points for c in curves for seg in c.segments]
    if not points:
        return
    # an arc's centre and radii too: a transform can squash a circle into an ellipse 1e16 mm long between two
    # ordinary end points (a fuzzed skewX(90)), and sampling it took the planar arrangement 11 s
    points += [np.asarray(seg.arc[:4], dtype=float) for c in curves for seg in c.segments if seg.arc is not None]
    every = np.abs(np.concatenate([np.asarray(p, dtype=float).reshape(-1) for p in points]))
    finite = bool(np.all(np.isfinite(every)))
    if finite and float(every.max()) <= MAX_COORDINATE_MM:
        return
    for c in curves:
        for seg in c.segments:
            if not np.all(np.isfinite(seg.points)):
                raise PatternError(f"{c.source or 'curve'}: non-finite coordinate in {_a(seg.kind)} segment")
    for c in curves:
        for seg in c.segments:
            big = float(np.max(np.abs(seg.points)))
            if big > MAX_COORDINATE_MM:
                raise PatternError(
                    f"{c.source or 'curve'}: coordinate {big:.3g} mm in {_a(seg.kind)} segment is beyond "
                    f"±{MAX_COORDINATE_MM:g} mm (100 km); check the file's units, width/height and viewBox"
                )
            arc = np.abs(np.asarray(seg.arc[:4], dtype=float)) if seg.arc is not None else np.zeros(0)
            if len(arc) and not (np.all(np.isfinite(arc)) and float(arc.max()) <= MAX_COORDINATE_MM):
                raise PatternError(
                    f"{c.source or 'curve'}: an arc with centre or radius {float(np.max(arc)):.3g} mm is beyond "
                    f"±{MAX_COORDINATE_MM:g} mm (100 km); check the file's transforms (a skew of 90° squashes a "
                    "circle into an endless ellipse)"
                )


def _check_positive(interval: float | None, tolerance: float | None) -> None:
    """Refuse an interval or tolerance that is not a positive number of mm (``None``: the default, not checked)."""
    for name, value in (("interval", interval), ("tolerance", tolerance)):
        if value is not None and not (value > 0 and math.isfinite(value)):
            raise PatternError(f"discretisation: {name} must be a positive number of mm, got {value!r}")


def _interval_above_merge(interval: float, merge_tolerance: float, warnings: list[str]) -> float:
    """``interval``, raised to the merge tolerance with a warning if below it: pieces shorter than that are welded
    together again (curves) or left as slivers below it (border subdivision, which runs after merging); never
    useful, and it multiplies the vertex count."""
    if interval >= merge_tolerance:
        return interval
    warnings.append(
        f"discretisation capped: interval {interval:g} mm is below the merge tolerance {merge_tolerance:g} mm; "
        f"used {merge_tolerance:g} mm"
    )
    return merge_tolerance


def _resolve_parameters(
    curves: list[CreaseCurve],
    interval: float | None,
    tolerance: float | None,
    merge_tolerance: float | None,
    warnings: list[str],
) -> tuple[float, float, float]:
    """Step 0: the scale-aware defaults for missing parameters, validated; interval raised to the merge tolerance."""
    size = sheet_size(curves)
    if 0.0 < size < MIN_SHEET_MM:
        raise PatternError(
            f"crease pattern: the sheet is only {size:.3g} mm across (minimum {MIN_SHEET_MM:g} mm); check the "
            "file's units, width/height and viewBox"
        )
    d_int, d_tol, d_merge = default_parameters(size or 1.0)
    interval = d_int if interval is None else float(interval)
    tolerance = d_tol if tolerance is None else float(tolerance)
    merge_tolerance = d_merge if merge_tolerance is None else float(merge_tolerance)
    _check_positive(interval, tolerance)
    if not (merge_tolerance >= 0 and math.isfinite(merge_tolerance)):
        raise PatternError(f"discretisation: merge tolerance must be ≥ 0 mm, got {merge_tolerance!r}")
    interval = _interval_above_merge(interval, merge_tolerance, warnings)
    tolerance_floor = max(merge_tolerance, size * 1e-6) * TOLERANCE_FLOOR_OF_MERGE
    if tolerance < tolerance_floor:
        # chords that fine are shorter than the merge tolerance on all but the flattest curves and are welded again
        warnings.append(
            f"discretisation capped: tolerance {tolerance:g} mm is below {TOLERANCE_FLOOR_OF_MERGE:g} × the merge "
            f"tolerance; used {tolerance_floor:g} mm"
        )
        tolerance = tolerance_floor
    return interval, tolerance, merge_tolerance


def _guard_explosion(
    curves: list[CreaseCurve], interval: float, tolerance: float, warnings: list[str]
) -> tuple[float, float]:
    """Explosion guard: estimate the segment count first, enlarge the parameters until the estimate is under the
    limit."""

    def estimated_count(interval: float, tolerance: float) -> float:
        estimate = 0.0
        for c in curves:
            for seg in c.segments:
                if not seg.is_straight:
                    estimate += _estimate_pieces(seg, interval, tolerance)
                elif c.assignment == "B":
                    estimate += max(1.0, _segment_length(seg) / interval)
                else:
                    estimate += 1.0
        return estimate

    estimate = first_estimate = estimated_count(interval, tolerance)
    if estimate > MAX_SEGMENTS:
        old_i, old_t = interval, tolerance
        target = 0.8 * MAX_SEGMENTS  # margin: the estimate runs up to ~12 % low (crossings, border pieces rounded up)
        for _ in range(8):  # pieces scale as 1/interval and 1/sqrt(tolerance)
            f = estimate / target
            interval, tolerance = interval * f, tolerance * f * f
            estimate = estimated_count(interval, tolerance)
            if estimate <= target:
                break
        warnings.append(
            f"discretisation capped: interval {old_i:g} mm and tolerance {old_t:g} mm would give about "
            f"{int(first_estimate)} segments (limit {MAX_SEGMENTS}); used interval {interval:.4g} mm and tolerance "
            f"{tolerance:.4g} mm"
        )
    return interval, tolerance


def _discretise_curves(
    curves: list[CreaseCurve],
    sources: list[str],
    interval: float,
    tolerance: float,
    merge_tolerance: float,
    warnings: list[str],
) -> _Pieces:
    """Steps 1–2: every drawn segment as polyline pieces, borders first (they win merges and duplicates)."""
    order = sorted(range(len(curves)), key=lambda k: PRIORITY.get(curves[k].assignment, 5))
    points: list[np.ndarray] = []  # each segment's polyline points, in order
    owner: list[int] = []  # its curve
    curved_flags: list[bool] = []
    total = 0
    hit_budget = False
    below_merge: list[int] = []  # curves whose chords had to be shorter than the merge tolerance
    cusps: list[tuple[int, np.ndarray]] = []  # (curve, point) of each cusp: a vertex of its polyline
    for k in order:
        c = curves[k]
        if c.assignment not in PRIORITY:
            raise PatternError(f"{sources[k]}: unknown assignment {c.assignment!r}")
        for seg in c.segments:
            if seg.is_straight:  # the common case, without the per-segment numpy calls of a curve
                pts = seg.points[[0, -1]]
                curved = False
            else:
                budget = max(2, MAX_SEGMENTS - total)
                cusp_t = _cusp_parameters(seg)
                pts, curved, worst = _segment_polyline(seg, interval, tolerance, budget, cusp_t)
                n = len(pts) - 1
                if n >= budget or worst > tolerance * (1 + 1e-9):
                    hit_budget = True
                if n > 1 and float(np.hypot(*np.diff(pts, axis=0).T).min()) < merge_tolerance:
                    below_merge.append(k)
                cusps += [(k, seg.evaluate(t)) for t in cusp_t]
            points.append(pts)
            owner.append(k)
            curved_flags.append(curved)
            total += len(pts) - 1
    # pieces a → b: consecutive points of one segment (every point but each segment's last starts one)
    every = np.concatenate(points).astype(float, copy=False).reshape(-1, 2)
    counts = np.array([len(p) - 1 for p in points], dtype=np.int64)
    first = np.delete(np.arange(len(every)), np.cumsum(counts + 1) - 1)
    if hit_budget:
        warnings.append(
            f"discretisation stopped refining at {MAX_SEGMENTS} segments: tolerance {tolerance:g} mm was not "
            "reached on every curve; pass a larger --tolerance"
        )
    if below_merge:
        warnings.append(
            f"tolerance {tolerance:g} mm needs curve chords shorter than the merge tolerance {merge_tolerance:g} mm "
            f"on {_describe_sources(sources, np.array(below_merge))}: points closer than that are merged, so those "
            "curves are followed less closely than asked; pass a larger --tolerance"
        )
    _warn_points(curves, sources, points, owner, merge_tolerance, warnings)
    if cusps:
        (k, at), more = cusps[0], f" and {len(cusps) - 1} more" if len(cusps) > 1 else ""
        warnings.append(
            f"{sources[k]} has a cusp at ({at[0]:.1f}, {at[1]:.1f}) mm{more}: the curve (nearly) stops and turns "
            "back there (its handles cross, or almost); it is folded as a corner of the crease. Move a handle if "
            "the point is not meant"
        )
    edge_poly = np.repeat(np.array(owner, dtype=np.int64), counts)
    assignment = np.array([c.assignment for c in curves], dtype="<U1")
    fold_angle = np.array([np.nan if c.fold_angle is None else float(c.fold_angle) for c in curves], dtype=float)
    return _Pieces(
        a=every[first],
        b=every[first + 1],
        polyline=edge_poly,
        from_curve=np.repeat(np.array(curved_flags, dtype=bool), counts),
        assignment=assignment[edge_poly],
        fold_angle=fold_angle[edge_poly],
    )


def _warn_points(
    curves: list[CreaseCurve],
    sources: list[str],
    points: list[np.ndarray],
    owner: list[int],
    merge_tolerance: float,
    warnings: list[str],
) -> None:
    """Warn about drawn curves that are a point (every sample within the merge tolerance of their first): they
    leave no crease. A valley under ``transform="scale(0)"`` vanished without a word (a CLI review session), while
    ``scale(0, 1)`` was warned about as a crease lying on the border."""
    spread = np.zeros(len(curves))
    for pts, k in zip(points, owner, strict=True):
        spread[k] = max(spread[k], float(np.max(np.hypot(*(pts - pts[0]).T))))
    dots = [k for k in range(len(curves)) if curves[k].segments and spread[k] <= merge_tolerance]
    if dots:
        warnings.append(
            f"{len(dots)} curve(s) drawn as a point (no length; a transform may scale them to nothing) left out: "
            f"{_describe_sources(sources, np.array(dots))}"
        )


def _planar_arrangement(
    pieces: _Pieces, merge_tolerance: float, sources: list[str]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step 3: merge close vertices, split crossings (X) and T-junctions, drop zero-length pieces.

    Returns ``(verts, edges, attrs)``, ``attrs`` indexing the pieces' attribute arrays."""
    # interleaved (start, end, start, end, ...) so "first representative" follows the drawing order
    verts, idx = _merge_points(np.stack([pieces.a, pieces.b], axis=1).reshape(-1, 2), merge_tolerance)
    m = len(pieces.a)
    edges = idx.reshape(m, 2)
    attrs = np.arange(m)  # index into the per-segment attribute arrays
    for _ in range(4):
        keep = edges[:, 0] != edges[:, 1]
        edges, attrs = edges[keep], attrs[keep]
        rec = _split_records(verts, edges, merge_tolerance, pieces.assignment[attrs] == "B")
        if len(rec[0]) == 0:
            break
        verts, edges, parent = _apply_splits(verts, edges, rec, merge_tolerance)
        attrs = attrs[parent]
        verts, idx = _merge_points(verts, merge_tolerance)
        edges = idx[edges]
    keep = edges[:, 0] != edges[:, 1]
    edges, attrs = edges[keep], attrs[keep]
    if len(edges) == 0:
        raise PatternError(
            f"crease pattern: every segment is shorter than the merge tolerance {merge_tolerance:g} mm "
            f"(sources: {_describe_sources(sources, pieces.polyline)})"
        )
    return verts, edges, attrs


def _remove_duplicates(
    edges: np.ndarray, attrs: np.ndarray, pieces: _Pieces, sources: list[str], warnings: list[str]
) -> tuple[np.ndarray, np.ndarray]:
    """Step 3 (end): of coinciding pieces keep the highest-priority assignment, warn when they disagree. Between
    pieces of equal priority, one that is not the last piece of its stroke wins over one that is: two creases drawn
    along one line from either side, each a hair past the crease between them (a valley from above, a mountain from
    below), overlap there, and the valley's overshoot had turned the mountain's first 0.3 mm into a valley (a
    designer session's curved Miura); each stroke now keeps its own side."""
    assign, angle, edge_poly = pieces.assignment, pieces.fold_angle, pieces.polyline
    key = np.sort(edges, axis=1)
    prio = np.array([PRIORITY[x] for x in assign[attrs].tolist()], dtype=np.int64)
    stroke = edge_poly[attrs].astype(np.int64)
    n_strokes = int(stroke.max()) + 1 if len(stroke) else 1
    at = edges.astype(np.int64) * n_strokes + stroke[:, None]  # (vertex, stroke) of both ends of every piece
    codes, counts = np.unique(at, return_counts=True)
    terminal = np.any(counts[np.searchsorted(codes, at)] == 1, axis=1)  # an end no other piece of its stroke has
    o = np.lexsort((np.arange(len(edges)), terminal, prio, key[:, 1], key[:, 0]))
    first = np.r_[True, np.any(key[o][1:] != key[o][:-1], axis=1)]
    winners = o[first]
    group = np.cumsum(first) - 1
    dup = o[~first]
    if len(dup):
        win_of_dup = winners[group[~first]]
        wa, da_ = attrs[win_of_dup], attrs[dup]
        differ = assign[wa] != assign[da_]
        angle_differ = ~differ & ~np.isclose(angle[wa], angle[da_], equal_nan=True)
        if differ.any():
            pairs = sorted(
                {
                    (sources[edge_poly[x]], assign[x], sources[edge_poly[y]], assign[y])
                    for x, y in zip(wa[differ].tolist(), da_[differ].tolist(), strict=True)
                }
            )
            shown = "; ".join(f"kept {s1} ({a1}) over {s2} ({a2})" for s1, a1, s2, a2 in pairs[:5])
            more = f"; and {len(pairs) - 5} more" if len(pairs) > 5 else ""
            warnings.append(
                f"{int(differ.sum())} segment(s) of creases with different roles lie on top of each other (drawn "
                f"twice, or within the merge tolerance of each other): {shown}{more}, by role (border > cut > "
                "mountain/valley > undriven > facet; of equal roles, the stroke that runs on past the piece, else the "
                "first drawn)"
            )
        if angle_differ.any():
            x, y = wa[angle_differ][0], da_[angle_differ][0]
            warnings.append(
                f"{int(angle_differ.sum())} segment(s) of creases with different fold angles lie on top of each other: "
                "kept "
                f"{sources[edge_poly[x]]} ({angle[x]:g}°) over {sources[edge_poly[y]]} ({angle[y]:g}°), ..."
            )
    winners = np.sort(winners)
    return edges[winners], attrs[winners]


def _stray_border_as_cuts(
    verts: np.ndarray,
    edges: np.ndarray,
    attrs: np.ndarray,
    pieces: _Pieces,
    sources: list[str],
    warnings: list[str],
) -> np.ndarray:
    """Step 4 (start): black (border) lines inside the sheet, no part of its outline, are read as cuts; one warning
    names them. Returns ``attrs`` with those edges pointing at cut copies of their pieces (appended to ``pieces``).

    A border is the outline of the sheet and of its holes. A black line from the edge into the sheet (a slit), across
    it (a packaging crease, drawn dashed black) or loose inside it made the outline look open ("2 loose ends" at the
    slit's ends), so creases past the edge were not trimmed and the triangulation could not tell paper from outside.
    A laser-cut designer means such a line as a cut, and a border edge inside the paper is meshed as one anyway.
    Stray: border pieces that hang off a loop (pruned from its 2-core), loop pieces off its outer boundary (chords),
    and pieces lying inside an outline without touching it. Border lines outside every outline that touch no loop
    are an open border and stay as they are."""
    bi = np.flatnonzero(pieces.assignment[attrs] == "B")
    be = edges[bi]
    incident: dict[int, list[int]] = {}  # border vertex → its border edges
    for k, (a, b) in enumerate(be.tolist()):
        incident.setdefault(a, []).append(k)
        incident.setdefault(b, []).append(k)
    core = _two_core(be, incident)
    if not core.any():
        return attrs
    outline = _outer_boundary(verts, be, core)
    looped = _joined(be, incident, core)
    mid = 0.5 * (verts[be[:, 0]] + verts[be[:, 1]])
    inside = _inside_border(mid, verts[be[outline, 0]], verts[be[outline, 1]])
    stray = ~outline & (looped | inside)
    if not stray.any():
        return attrs
    if np.isin(pieces.polyline[attrs[bi[stray]]], pieces.polyline[attrs[bi[outline]]]).any():
        # a stroke partly on the outline and partly inside it: two outlines cross (a notch drawn as a circle over
        # the edge), not a line inside the sheet; which side is paper is the designer's to say (_clip_to_border
        # refuses a border that crosses itself)
        return attrs
    named = bi[stray & inside]
    if len(named):
        warnings.append(
            f"black (border) line(s) inside the sheet: {_describe_sources(sources, pieces.polyline[attrs[named]])}; a "
            "border must be the sheet's outline, so they are read as cuts (draw a cut in green, a crease in red/blue)"
        )
    copies = attrs[bi[stray]]
    new = len(pieces.a) + np.arange(len(copies))
    for f in fields(pieces):
        values = getattr(pieces, f.name)
        setattr(pieces, f.name, np.concatenate([values, values[copies]]))
    pieces.assignment[new] = "C"
    pieces.fold_angle[new] = np.nan
    attrs = attrs.copy()
    attrs[bi[stray]] = new
    return attrs


def _two_core(e: np.ndarray, incident: dict[int, list[int]]) -> np.ndarray:
    """Which edges ``e`` (``incident``: vertex → its edges) are left when edges with a free end are pruned again and
    again: those on closed loops and on the paths between loops (the rest hangs off them or is an open line)."""
    degree = {v: len(ks) for v, ks in incident.items()}
    leaves = [v for v, d in degree.items() if d == 1]
    alive = np.ones(len(e), dtype=bool)
    while leaves:
        v = leaves.pop()
        if degree[v] != 1:
            continue
        k = next(k for k in incident[v] if alive[k])
        alive[k] = False
        for u in e[k].tolist():
            degree[u] -= 1
            if degree[u] == 1:
                leaves.append(u)
    return alive


def _joined(e: np.ndarray, incident: dict[int, list[int]], core: np.ndarray) -> np.ndarray:
    """Which edges ``e`` are connected to a ``core`` edge, through other edges (``incident``: vertex → its edges)."""
    joined = core.copy()
    stack = np.unique(e[core]).tolist()
    seen = set(stack)
    while stack:
        for k in incident[stack.pop()]:
            joined[k] = True
            for u in e[k].tolist():
                if u not in seen:
                    seen.add(u)
                    stack.append(u)
    return joined


def _outer_boundary(verts: np.ndarray, e: np.ndarray, core: np.ndarray) -> np.ndarray:
    """Which ``core`` edges lie on the outer boundary of their connected group: walked with the outside on the left,
    from each group's lowest leftmost vertex, turning at every vertex to the next edge clockwise."""
    around: dict[int, list[tuple[float, int, int]]] = {}  # vertex → (angle, neighbour, edge), counter-clockwise
    for k in np.flatnonzero(core).tolist():
        a, b = e[k].tolist()
        d = verts[b] - verts[a]
        around.setdefault(a, []).append((math.atan2(d[1], d[0]), b, k))
        around.setdefault(b, []).append((math.atan2(-d[1], -d[0]), a, k))
    slot: dict[tuple[int, int], int] = {}
    for v, lst in around.items():
        lst.sort()
        slot.update(((v, u), i) for i, (_, u, _) in enumerate(lst))
    on = np.zeros(len(e), dtype=bool)
    reached: set[int] = set()
    for v0 in sorted(around, key=lambda v: (verts[v, 0], verts[v, 1])):
        if v0 in reached:
            continue
        stack = [v0]
        reached.add(v0)
        while stack:
            for _, u, _ in around[stack.pop()]:
                if u not in reached:
                    reached.add(u)
                    stack.append(u)
        _, w, k = around[v0][-1]  # the first edge clockwise from due west: the outside is to the west of v0
        v = v0
        for _ in range(2 * len(e) + 2):
            on[k] = True
            _, nxt, k = around[w][slot[(w, v)] - 1]  # the next edge clockwise from the one we came along
            v, w = w, nxt
            if (v, w) == (v0, around[v0][-1][1]):
                break
    return on


def _close_open_border(
    curves: list[CreaseCurve], merge_tolerance: float, reach: float, warnings: list[str]
) -> list[CreaseCurve]:
    """Close a border left open at one place: when the border strokes together have exactly two loose ends (ends
    that meet no other border end within ``merge_tolerance``), a straight border stroke joins them, with a warning,
    unless one of them overshoots (:func:`_either_overshoots`; ``reach``: how near).

    A rectangle drawn as four points with Cyclic forgotten, or an outline whose last point misses its first by a
    fraction of a millimetre, is what the designer sees as the sheet's outline; left open, the border separated no
    paper from outside, so the crease nearest the gap became the sheet's edge and the strip beyond it was dropped.
    Borders open at several places are joined after the planar clean-up, where they close by a hair
    (:func:`_join_border_gaps`), and otherwise warned about where the segments are clipped. A black line whose loose
    end lies on or inside a closed border stroke (a slit from the edge, a line across or inside the sheet) is no gap
    in the outline: :func:`_stray_border_as_cuts` makes it a cut (closing it drew a straight chord across the sheet
    that was never drawn)."""
    ends = [
        (k, side, c.segments[0].points[0] if side == 0 else c.segments[-1].points[-1])
        for k, c in enumerate(curves)
        if c.assignment == "B" and not c.closed and c.segments
        for side in (0, 1)
    ]
    if len(ends) < 2:
        return curves
    pts = np.array([p for _, _, p in ends], dtype=np.float64)
    loose = np.flatnonzero(_ends_met(pts, merge_tolerance) % 2 == 0)  # an end met an odd number of times is joined
    if len(loose) != 2 or _on_or_inside_closed_border(pts[loose], curves, SNAP_FACTOR * merge_tolerance).any():
        return curves
    if _either_overshoots(curves, [ends[int(x)] for x in loose.tolist()], merge_tolerance, reach):
        return curves
    a, b = pts[loose[0]], pts[loose[1]]
    gap = float(np.hypot(*(b - a)))
    if gap <= merge_tolerance:
        return curves
    names = sorted({curves[ends[i][0]].source or f"curve {ends[i][0]}" for i in loose})
    corner = _lines_meet(a, _end_direction(curves, ends[loose[0]]), b, _end_direction(curves, ends[loose[1]]), reach)
    if corner is not None and min(np.hypot(*(corner - a)), np.hypot(*(corner - b))) > merge_tolerance:
        # a gap at a corner: both ends drawn on to it (a straight edge cut a chamfer off the corner, and a crease
        # drawn to the corner ended outside the sheet)
        closing = CreaseCurve(
            [CurveSegment("line", np.array([a, corner])), CurveSegment("line", np.array([corner, b]))],
            "B",
            None,
            source=f"the corner closing {' and '.join(names)}",
        )
        longest = float(max(np.hypot(*(corner - a)), np.hypot(*(corner - b))))
        warnings.append(
            f"the border is not closed ({', '.join(names)}): drew its loose ends at ({a[0]:.3f}, {a[1]:.3f}) and "
            f"({b[0]:.3f}, {b[1]:.3f}) mm on to the corner where their lines meet, ({corner[0]:.3f}, "
            f"{corner[1]:.3f}) mm, up to {longest:.4g} mm (close the outline where you drew it, e.g. Cyclic in "
            "Blender, Z in SVG)"
        )
        return [*curves, closing]
    closing = CreaseCurve(
        [CurveSegment("line", np.array([a, b]))], "B", None, source=f"the straight edge closing {' and '.join(names)}"
    )
    warnings.append(
        f"the border is not closed ({', '.join(names)}): joined its loose ends at ({a[0]:.3f}, {a[1]:.3f}) and "
        f"({b[0]:.3f}, {b[1]:.3f}) mm with a straight edge, {gap:.4g} mm long (close the outline where you drew it, "
        "e.g. Cyclic in Blender, Z in SVG)"
    )
    return [*curves, closing]


def _end_direction(curves: list[CreaseCurve], end: tuple[int, int, np.ndarray]) -> np.ndarray:
    """The direction a border stroke runs in at its loose ``end`` (stroke, side, point), outwards: along the chord of
    its last 1/1000 (a curve's tangent there)."""
    k, side, point = end
    seg = curves[k].segments[0 if side == 0 else -1]
    inner = seg.evaluate(np.array([1e-3 if side == 0 else 1.0 - 1e-3]))[0]
    return np.asarray(point, dtype=np.float64) - inner


def _either_overshoots(
    curves: list[CreaseCurve], ends: list[tuple[int, int, np.ndarray]], merge_tolerance: float, reach: float
) -> bool:
    """Whether the stroke of one of the loose border ``ends`` (stroke, side, point) crosses or touches another
    border piece within ``reach`` of it: it overshoots (a stroke drawn past its own start, lines past a corner), it
    is no gap to close, and its stub is trimmed later (:func:`_trim_border_stubs`)."""
    pieces = [
        (k, g, seg.evaluate(np.linspace(0.0, 1.0, 33)))
        for k, c in enumerate(curves)
        if c.assignment == "B"
        for g, seg in enumerate(c.segments)
    ]
    boxes = np.array([[*line.min(axis=0), *line.max(axis=0)] for _, _, line in pieces])
    return any(_overshoots(curves, end, pieces, boxes, merge_tolerance, reach) for end in ends)


def _overshoots(
    curves: list[CreaseCurve],
    end: tuple[int, int, np.ndarray],
    pieces: list[tuple[int, int, np.ndarray]],
    boxes: np.ndarray,
    tol: float,
    reach: float,
) -> bool:
    """Whether the stroke of ``end`` (its index, side and point) crosses or touches another border piece within
    ``reach`` of that end (``pieces``: stroke, segment and samples of each border piece, ``boxes`` their bounding
    boxes): an end drawn past a corner, or past the stroke's own start."""
    k, side, p = end
    own = 0 if side == 0 else len(curves[k].segments) - 1
    tail = curves[k].segments[own].evaluate(np.linspace(0.0, 1.0, 33) if side == 0 else np.linspace(1.0, 0.0, 33))
    within = np.hypot(*(tail - p).T) <= reach
    tail = tail[: max(2, int(np.argmin(within)) if not within.all() else len(tail))]
    lo, hi = tail.min(axis=0) - tol, tail.max(axis=0) + tol
    near = np.flatnonzero(np.all(boxes[:, :2] <= hi, axis=1) & np.all(boxes[:, 2:] >= lo, axis=1))
    for n in near.tolist():
        m, g, line = pieces[n]
        if (m, g) != (k, own) and _chains_meet(tail[:-1], tail[1:], line[:-1], line[1:], tol):
            return True
    return False


def _chains_meet(a0: np.ndarray, a1: np.ndarray, b0: np.ndarray, b1: np.ndarray, tol: float) -> bool:
    """Whether any segment ``a0[i]–a1[i]`` crosses any ``b0[j]–b1[j]``, or an end of one lies within ``tol`` of
    the other."""

    A0, A1, B0, B1 = a0[:, None], a1[:, None], b0[None], b1[None]
    r, q = A1 - A0, B1 - B0
    d1, d2 = _cross(r, B0 - A0), _cross(r, B1 - A0)
    d3, d4 = _cross(q, A0 - B0), _cross(q, A1 - B0)
    if np.any((d1 * d2 < 0) & (d3 * d4 < 0)):
        return True
    ends_a = np.concatenate([a0, a1[-1:]])
    ends_b = np.concatenate([b0, b1[-1:]])
    near_b = point_segment_distance(
        np.repeat(ends_a, len(b0), axis=0), np.tile(b0, (len(ends_a), 1)), np.tile(b1, (len(ends_a), 1))
    )
    near_a = point_segment_distance(
        np.repeat(ends_b, len(a0), axis=0), np.tile(a0, (len(ends_b), 1)), np.tile(a1, (len(ends_b), 1))
    )
    return bool(near_b.min() <= tol or near_a.min() <= tol)


def _on_or_inside_closed_border(points: np.ndarray, curves: list[CreaseCurve], tol: float) -> np.ndarray:
    """Which ``points`` lie inside, or within ``tol`` of, a closed border stroke (each sampled as a polygon)."""
    out = np.zeros(len(points), dtype=bool)
    for c in curves:
        if c.assignment != "B" or not c.closed or not c.segments:
            continue
        a = np.concatenate([s.evaluate(np.linspace(0.0, 1.0, 65)) for s in c.segments])
        b = np.roll(a, -1, axis=0)
        out |= _inside_border(points, a, b)
        out |= np.array([point_segment_distance(np.broadcast_to(q, a.shape), a, b).min() <= tol for q in points])
    return out


def _ends_met(pts: np.ndarray, tol: float) -> np.ndarray:
    """For each point, how many others lie within ``tol`` (near pairs from :func:`_candidate_pairs`' grid, the
    points taken as segments of no length: linear in the number of points, where all pairs would take quadratic
    memory on a border drawn as thousands of strokes)."""
    i, j = _candidate_pairs(pts, pts, tol)
    near = np.hypot(*(pts[i] - pts[j]).T) <= tol
    return np.bincount(np.concatenate([i[near], j[near]]), minlength=len(pts))


def _clip_to_border(
    verts: np.ndarray,
    edges: np.ndarray,
    attrs: np.ndarray,
    pieces: _Pieces,
    sources: list[str],
    size: float,
    tolerances: tuple[float, float],
    warnings: list[str],
    left: list[np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step 4: refuse a self-crossing border, warn about an open one, remove crease pieces outside a closed one and
    move crease ends just short of it onto it (:func:`_snap_short_ends`; ``size``: the sheet's; ``tolerances``:
    the merge tolerance and the curves' tolerance; ``left`` gets the ends that could not be moved)."""
    attrs = _stray_border_as_cuts(verts, edges, attrs, pieces, sources, warnings)
    reach = SHORT_OF_BORDER_FRACTION * size
    edges, attrs, past = _trim_border_stubs(verts, edges, attrs, pieces, sources, reach, warnings)
    n_before = len(edges)
    verts, edges, attrs = _join_border_gaps(verts, edges, attrs, pieces, sources, reach, warnings, tolerances[0])
    verts, edges, attrs = _split_at_joins(verts, edges, attrs, pieces, n_before, tolerances[0])
    edge_poly = pieces.polyline
    is_b, deg = _border_degree(len(verts), edges, attrs, pieces)
    if not is_b.any():
        return verts, edges, attrs
    crossing = np.flatnonzero((deg >= 4) & (deg % 2 == 0))
    if len(crossing):
        # four or more border pieces at one point: the outline crosses or touches itself, so which side is
        # paper is ambiguous (a figure-eight outline); the designer must redraw it
        at_b = is_b & np.isin(edges, crossing).any(axis=1)
        pts = _listed([f"({verts[v, 0]:.3f}, {verts[v, 1]:.3f})" for v in crossing])
        names = _describe_sources(sources, edge_poly[attrs[at_b]])
        raise PatternError(
            f"the border crosses or touches itself at {pts} mm ({names})"
            + (past or "; draw the outline of the sheet as one loop that does not cross itself")
        )
    open_v = np.flatnonzero(deg % 2 == 1)
    if len(open_v):
        pts = _listed([f"({verts[v, 0]:.3f}, {verts[v, 1]:.3f})" for v in open_v])
        warnings.append(f"the border is not closed: {len(open_v)} loose end(s) at {pts} mm")
        return verts, edges, attrs
    others = np.flatnonzero(~is_b)
    mid = 0.5 * (verts[edges[others, 0]] + verts[edges[others, 1]])
    inside = _inside_border(mid, verts[edges[is_b, 0]], verts[edges[is_b, 1]])
    outside = others[~inside]
    if len(outside):
        warnings.append(
            f"removed {len(outside)} crease segment(s) outside the border, from "
            f"{_describe_sources(sources, edge_poly[attrs[outside]])}"
        )
        keep = np.ones(len(edges), bool)
        keep[outside] = False
        edges, attrs = edges[keep], attrs[keep]
    return _snap_short_ends(verts, edges, attrs, pieces, sources, size, tolerances, warnings, left)


def _border_degree(n: int, edges: np.ndarray, attrs: np.ndarray, pieces: _Pieces) -> tuple[np.ndarray, np.ndarray]:
    """Which ``edges`` are border pieces (bool per edge), and how many of them meet at each of the ``n`` vertices."""
    is_b = pieces.assignment[attrs] == "B"
    return is_b, np.bincount(edges[is_b].ravel(), minlength=n)


MAX_GAP_ENDS = 400
"""Loose border ends beyond which :func:`_join_border_gaps` pairs none (its distances are all pairs)."""


def _join_border_gaps(
    verts: np.ndarray,
    edges: np.ndarray,
    attrs: np.ndarray,
    pieces: _Pieces,
    sources: list[str],
    reach: float,
    warnings: list[str],
    merge_tolerance: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Join the border's loose ends in pairs where that closes it: each the other's nearest loose end, within
    ``reach`` (:data:`SHORT_OF_BORDER_FRACTION` of the sheet), and the pieces they join left without a loose end
    (an outline drawn as pieces that miss each other by a hair at its corners), with one warning. Two pieces that
    meet at an angle are drawn on to the corner where their end pieces' lines meet (:func:`_corner_of`; the vertex
    there within ``merge_tolerance``, a crease's end drawn to the corner, or a new one returned in the vertices),
    others are joined by a straight border piece: the straight edge cut a tiny
    chamfer off each corner, and a crease drawn to the corner ended outside the sheet (a designer session in
    Blender). After the black lines inside the sheet became cuts (:func:`_stray_border_as_cuts`) and the stubs past
    its corners were trimmed: the slits of a kirigami lattice, and the paper bridges between them, stay as drawn
    (joined before the clean-up, a review session's lattice fell apart). A square drawn as four lines 0.1 mm apart
    at two corners folded nothing ("converged" in 0 iterations), at four "no paper left" (a designer session)."""
    is_b, deg = _border_degree(len(verts), edges, attrs, pieces)
    b_idx = np.flatnonzero(is_b)
    loose = np.flatnonzero(deg == 1)
    if len(loose) < 2 or len(loose) > MAX_GAP_ENDS:
        return verts, edges, attrs
    q = verts[loose]
    d = np.hypot(*(q[:, None, :] - q[None, :, :]).transpose(2, 0, 1))
    np.fill_diagonal(d, np.inf)
    nearest = np.argmin(d, axis=1)
    pairs = [(a, int(b)) for a, b in enumerate(nearest.tolist()) if b > a and nearest[b] == a and d[a, b] <= reach]
    if not pairs:
        return verts, edges, attrs
    # keep the pairs whose border pieces (joined at vertices) are left with no loose end: an outline closed
    ends = np.array(pairs, dtype=np.int64)
    group = connected_components(
        len(verts), np.r_[edges[b_idx, 0], loose[ends[:, 0]]], np.r_[edges[b_idx, 1], loose[ends[:, 1]]]
    )
    paired = {x for pair in pairs for x in pair}
    still_open = {int(group[loose[x]]) for x in range(len(loose)) if x not in paired}
    pairs = [(a, b) for a, b in pairs if int(group[loose[a]]) not in still_open]
    if not pairs:
        return verts, edges, attrs
    # each new piece takes the attributes of the border piece at its first end (its role, source)
    at = {int(v): k for k in b_idx.tolist() for v in edges[k].tolist()}
    new_verts: list[np.ndarray] = []
    new_edges: list[tuple[int, int]] = []
    new_attrs: list[int] = []
    corners: list[float] = []
    straight: list[float] = []
    for a, b in pairs:
        va, vb = int(loose[a]), int(loose[b])
        attr = int(attrs[at[va]])
        corner = _corner_of(verts, edges[at[va]], va, edges[at[vb]], vb, reach)
        near = np.hypot(*(verts - corner).T) if corner is not None else None
        c = int(np.argmin(near)) if near is not None else -1
        if c < 0 or (c in (va, vb) and near[c] <= merge_tolerance):  # no corner, or an end already at it: straight
            new_edges.append((va, vb))
            new_attrs.append(attr)
            (straight if c < 0 else corners).append(float(d[a, b]))
            continue
        if near[c] > merge_tolerance:
            c = len(verts) + len(new_verts)
            new_verts.append(corner)
        new_edges += [(va, c), (c, vb)]
        new_attrs += [attr, int(attrs[at[vb]])]
        corners.append(float(max(np.hypot(*(corner - verts[va])), np.hypot(*(corner - verts[vb])))))
    where = _listed([f"({verts[loose[a], 0]:.3f}, {verts[loose[a], 1]:.3f})" for a, _ in pairs])
    names = _describe_sources(sources, pieces.polyline[np.array(new_attrs)])
    how = []
    if corners:
        how.append(f"{len(corners)} drawn on to the corner where their lines meet (up to {max(corners):.4g} mm)")
    if straight:
        how.append(f"{len(straight)} joined by a straight edge (up to {max(straight):.4g} mm long)")
    warnings.append(
        f"the border is not closed at {len(pairs)} place(s) ({names}): {'; '.join(how)}, at {where} mm (make the "
        "pieces of the outline meet where you drew them)"
    )
    verts = np.concatenate([verts, np.array(new_verts).reshape(-1, 2)])
    edges = np.concatenate([edges, np.array(new_edges, dtype=edges.dtype)])
    return verts, edges, np.concatenate([attrs, np.array(new_attrs, dtype=attrs.dtype)])


def _split_at_joins(
    verts: np.ndarray, edges: np.ndarray, attrs: np.ndarray, pieces: _Pieces, first: int, merge_tolerance: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split the strokes the border pieces added by :func:`_join_border_gaps` (edges from ``first`` on) cross or pass
    through, and those pieces where they are crossed: the join comes after the planar clean-up, and a crease drawn
    past a corner whose outline had a gap crossed the new corner (or its chamfer) without a vertex there, so it was
    neither trimmed nor meshed ("pattern edges … cross or touch", a reviewer's square). A crossing within the merge
    tolerance of a vertex uses that vertex."""
    if first >= len(edges):
        return verts, edges, attrs
    others = np.flatnonzero(pieces.assignment[attrs[:first]] != "B")
    if not len(others):
        return verts, edges, attrs
    a, b = verts[edges[others, 0]], verts[edges[others, 1]]
    cuts: dict[int, list[tuple[float, int]]] = {}
    new_verts: list[np.ndarray] = []

    def vertex_at(x: np.ndarray) -> int:
        pts = np.concatenate([verts, np.array(new_verts).reshape(-1, 2)])
        near = np.hypot(*(pts - x).T)
        k = int(np.argmin(near))
        if near[k] <= merge_tolerance:
            return k
        new_verts.append(x)
        return len(pts)

    for k in range(first, len(edges)):
        p, q = verts[edges[k, 0]], verts[edges[k, 1]]
        r, sd = q - p, b - a
        den = r[0] * sd[:, 1] - r[1] * sd[:, 0]
        w = a - p
        with np.errstate(divide="ignore", invalid="ignore"):
            u = (w[:, 0] * sd[:, 1] - w[:, 1] * sd[:, 0]) / den  # along the new piece
            t = (w[:, 0] * r[1] - w[:, 1] * r[0]) / den  # along the stroke
        hit = (np.abs(den) > 0) & (u >= 0.0) & (u <= 1.0) & (t > 0.0) & (t < 1.0)
        for j in np.flatnonzero(hit).tolist():
            v = vertex_at(p + u[j] * r)
            if v not in edges[others[j]]:
                cuts.setdefault(int(others[j]), []).append((float(t[j]), v))
            if v not in edges[k]:
                cuts.setdefault(k, []).append((float(u[j]), v))
        for end in edges[k]:  # a stroke passing through a new corner (within the merge tolerance) is split there
            near = point_segment_distance(np.broadcast_to(verts[end], a.shape), a, b)
            for j in np.flatnonzero(near <= merge_tolerance).tolist():
                if end not in edges[others[j]]:
                    along = float(np.dot(verts[end] - a[j], sd[j]) / max(np.dot(sd[j], sd[j]), 1e-300))
                    cuts.setdefault(int(others[j]), []).append((along, int(end)))
    if not cuts:
        return verts, edges, attrs
    keep = np.ones(len(edges), dtype=bool)
    added, added_attrs = [], []
    for k, splits in cuts.items():
        chain = [int(edges[k, 0]), *[v for _, v in sorted(set(splits))], int(edges[k, 1])]
        chain = [v for i, v in enumerate(chain) if i == 0 or v != chain[i - 1]]
        keep[k] = False
        added += list(zip(chain[:-1], chain[1:], strict=True))
        added_attrs += [int(attrs[k])] * (len(chain) - 1)
    verts = np.concatenate([verts, np.array(new_verts).reshape(-1, 2)])
    edges = np.concatenate([edges[keep], np.array(added, dtype=edges.dtype).reshape(-1, 2)])
    return verts, edges, np.concatenate([attrs[keep], np.array(added_attrs, dtype=attrs.dtype)])


CORNER_MIN_DEG = 15.0
"""Border pieces whose ends miss each other meet at a corner (:func:`_corner_of`) when their end pieces turn by at
least this much; nearer to straight on, the corner is ill-defined and the ends are joined by a straight edge."""


def _corner_of(
    verts: np.ndarray, piece_a: np.ndarray, va: int, piece_b: np.ndarray, vb: int, reach: float
) -> np.ndarray | None:
    """Where the border pieces ``piece_a`` (ending at loose end ``va``) and ``piece_b`` (at ``vb``) meet when each is
    drawn on straight past its end: the crossing of their lines, ahead of both ends and within ``reach`` of each.
    None when they turn by less than :data:`CORNER_MIN_DEG` or the crossing is not ahead within reach."""
    pa, pb = verts[va], verts[vb]
    da = pa - verts[int(piece_a[0] if piece_a[1] == va else piece_a[1])]
    db = pb - verts[int(piece_b[0] if piece_b[1] == vb else piece_b[1])]
    return _lines_meet(pa, da, pb, db, reach)


def _lines_meet(pa: np.ndarray, da: np.ndarray, pb: np.ndarray, db: np.ndarray, reach: float) -> np.ndarray | None:
    """Where the rays from ``pa`` along ``da`` and from ``pb`` along ``db`` meet, each within ``reach`` of its start
    (a start already there counts); None when they turn by less than :data:`CORNER_MIN_DEG`."""
    la, lb = float(np.hypot(*da)), float(np.hypot(*db))
    if la == 0.0 or lb == 0.0:
        return None
    da, db = da / la, db / lb
    den = float(da[0] * db[1] - da[1] * db[0])
    if abs(den) < math.sin(math.radians(CORNER_MIN_DEG)):
        return None
    w = pb - pa
    s = float(w[0] * db[1] - w[1] * db[0]) / den  # pa + s·da = pb + t·db
    t = float(w[0] * da[1] - w[1] * da[0]) / den
    slack = 1e-9 * reach  # an end already at the corner (a piece drawn to it, its neighbour short of it)
    if not (-slack <= s <= reach and -slack <= t <= reach):
        return None
    return pa + s * da


def _trim_border_stubs(
    verts: np.ndarray,
    edges: np.ndarray,
    attrs: np.ndarray,
    pieces: _Pieces,
    sources: list[str],
    reach: float,
    warnings: list[str],
) -> tuple[np.ndarray, np.ndarray, str]:
    """Remove the border's stubs: a run of border pieces from a loose end to where three or more border pieces
    meet, at most ``reach`` long (:data:`SHORT_OF_BORDER_FRACTION` of the sheet), with a warning. A square drawn as
    four lines 0.3 mm past its corners (by eye, or a CAD program's lines) crosses itself at every corner and was
    refused ("the border crosses or touches itself"), where a crease drawn past the border is trimmed. Also
    returns, for a longer stub (up to ten times that), the clause the refusal of the self-crossing border it leaves
    adds ("" if none): it said to draw one loop, not that the lines overshoot."""
    is_b, deg = _border_degree(len(verts), edges, attrs, pieces)
    if not is_b.any():
        return edges, attrs, ""
    b_idx = np.flatnonzero(is_b)
    incident: dict[int, list[int]] = {}
    for k in b_idx.tolist():
        for v in edges[k].tolist():
            incident.setdefault(v, []).append(k)
    drop: list[int] = []
    lengths: list[float] = []
    long_stubs: list[tuple[int, float]] = []  # (where it meets the outline, length) of those not trimmed
    for start in np.flatnonzero(deg == 1).tolist():
        run, v, length = [], start, 0.0
        k = incident[start][0]
        while True:
            run.append(k)
            w = int(edges[k, 0] if edges[k, 1] == v else edges[k, 1])
            length += float(np.hypot(*(verts[w] - verts[v])))
            if length > 10 * reach or deg[w] != 2:
                break
            v, k = w, next(e for e in incident[w] if e != k)
        if length <= reach and deg[w] >= 3:
            drop += run
            lengths.append(length)
        elif deg[w] >= 3 and length <= 10 * reach:
            long_stubs.append((w, length))
    past = ""  # a stub left makes the outline cross itself: the refusal says where and how long
    if long_stubs:
        w, length = long_stubs[0]
        past = (
            f"; it is drawn on past itself by {length:.3g} mm at ({verts[w, 0]:.3f}, {verts[w, 1]:.3f}) mm, more "
            f"than 1 % of the sheet ({reach:.3g} mm, what is trimmed): end the lines where they meet"
        )
    if not drop:
        return edges, attrs, past
    keep = np.ones(len(edges), dtype=bool)
    keep[drop] = False
    names = _describe_sources(sources, pieces.polyline[attrs[drop]])
    warnings.append(
        f"trimmed {len(lengths)} border stub(s) drawn past where the outline meets itself, up to "
        f"{max(lengths):.3g} mm long, from {names}"
    )
    return edges[keep], attrs[keep], past


class _EndMover:
    """Moves free ends of segments onto other segments, one at a time: onto a vertex of the target within the merge
    tolerance, else onto a new vertex that splits it (later moves see the splits of earlier ones)."""

    def __init__(self, verts: np.ndarray, edges: np.ndarray, attrs: np.ndarray, merge_tolerance: float):
        self.verts, self.edges, self.attrs = verts, edges.copy(), attrs.copy()
        self.merge_tolerance = merge_tolerance
        self.new_verts: list[np.ndarray] = []
        self.extra_edges: list[tuple[int, int]] = []
        self.extra_attrs: list[int] = []

    def current(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Vertices, edges and their attributes as split so far."""
        return (
            np.concatenate([self.verts, np.array(self.new_verts).reshape(-1, 2)]),
            np.concatenate([self.edges, np.array(self.extra_edges, dtype=self.edges.dtype).reshape(-1, 2)]),
            np.concatenate([self.attrs, np.array(self.extra_attrs, dtype=self.attrs.dtype)]),
        )

    def points(self, ids: np.ndarray) -> np.ndarray:
        """Positions of vertices ``ids`` (old or added)."""
        ids = np.asarray(ids, dtype=np.int64)
        out = np.empty((len(ids), 2))
        old = ids < len(self.verts)
        out[old] = self.verts[ids[old]]
        if not old.all():
            out[~old] = np.array(self.new_verts).reshape(-1, 2)[ids[~old] - len(self.verts)]
        return out

    def rows(self, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Vertex pairs and attributes of edges ``idx`` (indices into :meth:`current`)."""
        idx = np.asarray(idx, dtype=np.int64)
        pairs, attrs = np.empty((len(idx), 2), dtype=np.int64), np.empty(len(idx), dtype=self.attrs.dtype)
        old = idx < len(self.edges)
        pairs[old], attrs[old] = self.edges[idx[old]], self.attrs[idx[old]]
        if not old.all():
            extra = idx[~old] - len(self.edges)
            pairs[~old] = np.array(self.extra_edges, dtype=np.int64).reshape(-1, 2)[extra]
            attrs[~old] = np.array(self.extra_attrs, dtype=self.attrs.dtype)[extra]
        return pairs, attrs

    def n_edges(self) -> int:
        return len(self.edges) + len(self.extra_edges)

    def destination(self, target_edge: int, foot: np.ndarray, snap: float = 0.0) -> tuple[int, np.ndarray]:
        """Where :meth:`move` puts an end aimed at ``foot`` on edge ``target_edge``: ``(vertex, point)``, the end of
        that edge within ``snap`` (at least the merge tolerance) of ``foot``, else ``(-1, foot)`` (a new vertex)."""
        (ends,), _ = self.rows([target_edge])
        at = self.points(ends)
        near = np.hypot(*(at - foot).T)
        k = int(np.argmin(near))
        if near[k] <= max(self.merge_tolerance, snap):
            return int(ends[k]), at[k]
        return -1, foot

    def move(self, w: int, side: int, target_edge: int, foot: np.ndarray, snap: float = 0.0) -> bool:
        """End ``side`` of edge ``w`` onto ``foot``, a point of edge ``target_edge`` (an index into
        :meth:`current`), or onto an end of that edge within ``snap`` (at least the merge tolerance) of it
        (:meth:`destination`); False when that would collapse ``w``."""
        (ends,), (attr,) = self.rows([target_edge])
        target, _ = self.destination(target_edge, foot, snap)
        if target < 0:  # split the target piece at the foot
            target = len(self.verts) + len(self.new_verts)
            self.new_verts.append(foot)
            if target_edge < len(self.edges):
                self.edges[target_edge] = (ends[0], target)
            else:
                self.extra_edges[target_edge - len(self.edges)] = (int(ends[0]), target)
            self.extra_edges.append((target, int(ends[1])))
            self.extra_attrs.append(int(attr))
        if target == self.edges[w, 1 - side]:
            return False
        self.edges[w, side] = target
        return True


def _untangled_landing(
    mover: _EndMover, w: int, side: int, border: np.ndarray, foot: np.ndarray, dist: np.ndarray, reach: float
) -> int | None:
    """Which border piece (an index into ``border``) the free end ``side`` of edge ``w`` lands on when moved onto
    the border (:func:`_snap_short_ends`): the nearest point of the border (``foot``, ``dist`` per piece), or, where
    the moved end would cross or touch another stroke (:func:`_join_tangles`), the nearest end of a border piece
    within ``reach`` that it would not (two creases drawn towards one point of the border, stopping short of it
    interleaved, meet there); None where no landing within ``reach`` is clear. Moved straight onto the border, the
    end of a crease drawn by eye beside another crossed it and the pattern was refused: "edges … cross" (two
    lines drawn to a border point, stopping 0.1 and 0.5 mm short)."""
    pts, all_e, _ = mover.current()
    tip_v, back_v = int(mover.edges[w, side]), int(mover.edges[w, 1 - side])
    obstacle = np.ones(len(all_e), dtype=bool)
    obstacle[w] = False
    tol = mover.merge_tolerance
    # a piece that already passes within the tolerance of a vertex as drawn (its start beside a vertex of a curved
    # border's chords) is judged by crossings only: that touch is the drawing's, not the move's
    drawn = _join_tangles(pts, all_e, obstacle, (back_v, tip_v), (w, tip_v), pts[tip_v], tol)

    def tangles(piece: int, vertex: int, at: np.ndarray) -> bool:
        return _join_tangles(pts, all_e, obstacle, (back_v, tip_v), (piece, vertex), at, 0.0 if drawn else tol)

    k = int(np.argmin(dist))
    ends = all_e[border]  # (pieces, 2): the border's vertices, each with a piece it bounds
    near = np.linalg.norm(pts[ends] - pts[tip_v], axis=-1)  # (pieces, 2)
    corner = _corner_ahead(pts, ends, near, pts[tip_v], pts[tip_v] - pts[back_v], float(dist[k]), reach, tol)
    if corner is not None:
        piece, end = corner
        vertex = int(ends[piece, end])
        creases = obstacle.copy()
        creases[border] = False  # a piece along a side of the sheet is the corner's own business
        clear = vertex != back_v and not _lies_along(pts, all_e[creases], vertex, back_v)
        if clear and not tangles(int(border[piece]), vertex, pts[vertex]):
            foot[piece], dist[piece] = pts[vertex], near[piece, end]
            return piece
    dest_v, dest = mover.destination(int(border[k]), foot[k])
    if not tangles(int(border[k]), dest_v, dest):
        return k
    for flat in np.argsort(near, axis=None, kind="stable"):
        piece, end = divmod(int(flat), 2)
        if near[piece, end] > reach:
            break
        vertex = int(ends[piece, end])
        if vertex == back_v:
            continue
        if not tangles(int(border[piece]), vertex, pts[vertex]):
            foot[piece], dist[piece] = pts[vertex], near[piece, end]
            return piece
    return None


ALONG_DEG = 1.0
"""A piece drawn on to a corner lies along a stroke already there when their directions from the corner are within
this angle (:func:`_lies_along`)."""


def _lies_along(pts: np.ndarray, edges: np.ndarray, corner: int, back: int) -> bool:
    """Whether the piece ``back → corner`` (a crease end drawn on to ``corner``) would lie along another crease at
    the corner: one of ``edges`` leaves the corner within :data:`ALONG_DEG` of the piece's direction.
    :func:`_join_tangles` sees crossings and vertices passed near, not a piece on top of another that ends at the
    same two vertices: a valley that crossed a diagonal just before the corner was drawn on to the corner along the
    diagonal's last piece, and the overlap was then dropped as "drawn twice" (a reviewer's drawing)."""
    at = np.flatnonzero((edges == corner).any(axis=1))
    if not len(at):
        return False
    other = np.where(edges[at, 0] == corner, edges[at, 1], edges[at, 0])
    d = pts[other] - pts[corner]
    u = pts[back] - pts[corner]
    cos = (d @ u) / np.maximum(np.hypot(*d.T) * float(np.hypot(*u)), 1e-300)
    return bool(np.any(cos >= math.cos(math.radians(ALONG_DEG))))


CORNER_PULL = 2.0
"""A crease end moved onto the border lands on a corner of it within this many times its distance from the border
(or on a corner it points at: :func:`_corner_ahead`), not on a side beside the corner."""


def _corner_ahead(
    pts: np.ndarray,
    ends: np.ndarray,
    near: np.ndarray,
    tip: np.ndarray,
    direction: np.ndarray,
    gap: float,
    reach: float,
    tol: float,
) -> tuple[int, int] | None:
    """The corner of the border a crease end short of it (at ``tip``) is drawn towards, as ``(piece, end)`` of
    ``ends`` (the border pieces' vertices; ``near`` their distances from ``tip``), or None. A corner is a border
    vertex of two pieces turning by :data:`CORNER_MIN_DEG` or more (or of any other number of pieces); it is the
    landing when it lies within ``reach`` and within :data:`CORNER_PULL` × ``gap`` (the end's distance from the
    border), or ahead of the end along its last piece (``direction``) with the ray passing it by no more than
    ``gap`` (or the merge tolerance ``tol``). Moved to the nearest point of a side, an end drawn towards a corner
    and stopping 0.3 mm short landed 0.05–0.3 mm from the corner: a border piece that short, and a sliver
    triangle beside it."""
    length = float(np.hypot(*direction))
    unit = direction / length if length > 0 else np.zeros(2)
    within = np.flatnonzero(near.ravel() <= reach)
    for flat in within[np.argsort(near.ravel()[within], kind="stable")].tolist():
        piece, end = divmod(flat, 2)
        vertex = int(ends[piece, end])
        at = np.flatnonzero((ends == vertex).any(axis=1))
        if len(at) == 2:  # a corner only where its two pieces turn
            (a,), (b,) = (ends[i][ends[i] != vertex] for i in at)
            da, db = pts[vertex] - pts[a], pts[b] - pts[vertex]
            turn = abs(float(_cross(da, db))) / max(float(np.hypot(*da) * np.hypot(*db)), 1e-300)
            if turn < math.sin(math.radians(CORNER_MIN_DEG)) and float(np.dot(da, db)) > 0:
                continue
        rel = pts[vertex] - tip
        pulled = near[piece, end] <= CORNER_PULL * gap
        aimed = float(np.dot(rel, unit)) > 0 and abs(float(_cross(unit, rel))) <= max(gap, tol)
        if pulled or aimed:
            return piece, end
    return None


def _warn_left_short(
    verts: np.ndarray, edges: np.ndarray, assign: np.ndarray, left: list[np.ndarray], warnings: list[str]
) -> None:
    """Warn about the crease ends :func:`_snap_short_ends` left short of the border (``left``) that are still free
    ends after the near-miss join: they end inside the paper."""
    if not left:
        return
    which, sides = _loose_ends(edges, assign, len(verts))
    free = verts[edges[which, sides]]
    still = [q for q in left if len(free) and float(np.min(np.hypot(*(free - q).T))) == 0.0]
    if still:
        where = _listed([f"({q[0]:.3f}, {q[1]:.3f})" for q in still])
        warnings.append(
            f"{len(still)} crease end(s) stop short of the border at {where} mm, where moving them onto it would "
            f"cross or touch another crease: left where drawn (they end inside the paper); draw them to the border"
        )


def _loose_ends(edges: np.ndarray, assign: np.ndarray, n_verts: int) -> tuple[np.ndarray, np.ndarray]:
    """Free ends of creases: ``(edge, side)`` index arrays of segment ends at a vertex of degree 1. Not of cuts: the
    paper between a cut's end and the border or another cut is a bridge that holds a flap (a kirigami tab), and
    joining it cut a reviewer's sheets apart."""
    degree = np.bincount(edges.ravel(), minlength=n_verts)
    loose = (degree[edges] == 1) & np.isin(assign, ["M", "V", "U"])[:, None]
    return np.nonzero(loose)


def _snap_short_ends(
    verts: np.ndarray,
    edges: np.ndarray,
    attrs: np.ndarray,
    pieces: _Pieces,
    sources: list[str],
    size: float,
    tolerances: tuple[float, float],
    warnings: list[str],
    left: list[np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step 4 (end): free ends of creases (not cuts: :func:`_loose_ends`) that stop just short of the closed border
    (within :data:`SHORT_OF_BORDER_FRACTION` of the sheet) are moved onto it, at the nearest point of the border (a
    vertex of it within the merge tolerance, else a new one that splits its piece), with a warning naming them when
    the gap was beyond the merge tolerance, or beyond the curves' tolerance where the border piece is a chord of a
    curve (``tolerances``: both). A crease drawn exactly onto a curved hole ends on the curve, up to the tolerance
    off its chord: the warning told a designer to draw to the border where they had (0.06 mm at a 5 mm interval).

    Drawn "to the edge" by eye, a crease often stops a few tenths of a millimetre short. Left there, it ended inside
    the paper at both ends and could not fold without stretching it: the verdict said the pattern "does not fold as
    assigned" although the crease folded (a 150 mm sheet, gaps of 0.1 mm), and an end exactly at the merge
    tolerance was joined to the border while the other, 1e-14 mm farther, was not.

    An end that would cross or touch another stroke wherever it landed (:func:`_untangled_landing`) stays where it
    is; its position goes to ``left`` (the near-miss join may still draw it onto the stroke ahead of it;
    :func:`_warn_left_short` names those that stay inside the paper)."""
    assign = pieces.assignment[attrs]
    which, sides = _loose_ends(edges, assign, len(verts))
    if not len(which):
        return verts, edges, attrs
    reach = SHORT_OF_BORDER_FRACTION * size
    ba, bb = verts[edges[assign == "B", 0]], verts[edges[assign == "B", 1]]
    ends = verts[edges[which, sides]]
    gaps = np.array([point_segment_distance(np.broadcast_to(q, ba.shape), ba, bb).min() for q in ends])
    short = (gaps > 0.0) & (gaps <= reach)
    if not short.any():
        return verts, edges, attrs
    merge_tolerance, tolerance = tolerances
    mover = _EndMover(verts, edges, attrs, merge_tolerance)
    moved: list[tuple[float, np.ndarray, int]] = []
    left = [] if left is None else left
    order = np.argsort(gaps[short], kind="stable")  # nearest first: an end beside one moved before can land with it
    pending = list(zip(which[short][order].tolist(), sides[short][order].tolist(), strict=True))
    for last_pass in (False, True):  # an end with no clear landing is tried again once the others have moved
        waiting = []
        for w, side in pending:  # the border as split by the ends moved before
            pts, all_e, all_a = mover.current()
            border = np.flatnonzero(pieces.assignment[all_a] == "B")
            p = pts[edges[w, side]]
            a, b = pts[all_e[border, 0]], pts[all_e[border, 1]]
            foot = segment_foot(np.broadcast_to(p, a.shape), a, b)
            dist = np.hypot(*(p - foot).T)
            k = _untangled_landing(mover, w, side, border, foot, dist, reach)
            if k is None:
                waiting.append((w, side))
                continue
            target, at = int(border[k]), foot[k]
            quiet = tolerance if pieces.from_curve[all_a[target]] else merge_tolerance  # a chord, or the drawn line
            if mover.move(w, side, target, at) and dist[k] > max(quiet, merge_tolerance) * (1.0 + 1e-6):
                moved.append((float(dist[k]), p, int(attrs[w])))
        if len(waiting) == len(pending) or last_pass:
            left.extend(mover.current()[0][edges[w, side]] for w, side in waiting)
            break
        pending = waiting
    if moved:
        where = _listed([f"{g:.2g} mm at ({q[0]:.3f}, {q[1]:.3f})" for g, q, _ in moved])
        warnings.append(
            f"{len(moved)} crease end(s) stopped short of the border and were moved onto it ({where}), from "
            f"{_describe_sources(sources, pieces.polyline[[m[2] for m in moved]])}; a crease must reach the "
            f"border to fold without stretching the paper, so draw creases to the border (an end more than "
            f"{reach:.2g} mm inside is left where it is drawn)"
        )
    return mover.current()


END_TO_END_DEG = 30.0
"""A crease end joins the free end of another stroke of the same role and angle (one crease drawn as two strokes)
only when the two point at each other within this angle."""

NEAR_MISS_CONE_DEG = 45.0
"""A free crease end is joined to another crease only when that crease lies ahead of it: within this angle of the
direction the end's last piece points in (a T-junction drawn short, a crease drawn as two strokes that miss), never
beside it (a pleat ending next to its neighbour)."""


def _sheet_width(verts: np.ndarray, edges: np.ndarray, assign: np.ndarray, size: float) -> float:
    """The sheet's width: its outline's smaller extent along its principal axes (all vertices without a border),
    so a strip turned 45° has the width it has drawn straight (its bounding box's smaller side was 15× more)."""
    outline = np.unique(edges[assign == "B"]) if (assign == "B").any() else np.unique(edges)
    p = verts[outline] - verts[outline].mean(axis=0)
    if len(p) < 2:
        return size
    _, axes = np.linalg.eigh(p.T @ p)
    width = float(np.ptp(p @ axes, axis=0).min())
    return width if width > 0 else size


def _join_tangles(
    pts: np.ndarray,
    edges: np.ndarray,
    obstacle: np.ndarray,
    piece: tuple[int, int],
    onto: tuple[int, int],
    at: np.ndarray,
    tol: float,
) -> bool:
    """Whether drawing a free end on leaves what the planar clean-up (step 3) would have split. The piece runs from
    vertex ``back`` to ``at`` (``piece = (back, tip)``: ``tip`` is the free end it leaves), a point of edge ``target``
    (``onto = (target, dest)``: ``dest`` the vertex at ``at``, or -1 for a new one that splits ``target``); the
    ``obstacle`` edges (bool per edge) are the others that stay. True if the piece properly crosses an obstacle
    that does not end at ``back`` or ``dest``, or passes within ``tol`` of a vertex (of an obstacle or of
    ``target``), or its new vertex lies within ``tol`` of an obstacle.

    The clean-up is over by then, so such a join left two segments crossing, or a vertex inside a segment, for good:
    an end aimed past a junction it misses by a hair was drawn on past it, or snapped onto the end of the piece it
    hit and crossed a stroke at the junction (the crossing was tested on the way to the unsnapped point)."""
    back, tip = piece
    target, dest = onto
    p = pts[back]
    other = obstacle.copy()
    other[target] = False
    e = edges[other]
    a, b = pts[e[:, 0]], pts[e[:, 1]]
    apart = ~np.any((e == back) | (e == dest), axis=1)
    r, s = np.broadcast_to(at - p, a.shape), b - a
    d1, d2 = _cross(r, a - p), _cross(r, b - p)
    d3, d4 = _cross(s, p - a), _cross(s, at - a)
    scale = float(np.hypot(*(at - p))) * np.hypot(*s.T) * 1e-12
    if np.any(apart & (d1 * d2 < -(scale**2)) & (d3 * d4 < -(scale**2))):
        return True
    near = np.zeros(len(pts), dtype=bool)
    near[e] = True
    near[edges[target]] = True
    near[[back, tip, dest] if dest >= 0 else [back, tip]] = False
    ends = np.broadcast_to(p, (int(near.sum()), 2)), np.broadcast_to(at, (int(near.sum()), 2))
    if np.any(point_segment_distance(pts[near], *ends) < tol):
        return True
    return dest < 0 and bool(np.any(point_segment_distance(np.broadcast_to(at, a.shape), a, b) < tol))


def _join_near_misses(
    verts: np.ndarray,
    edges: np.ndarray,
    attrs: np.ndarray,
    pieces: _Pieces,
    sources: list[str],
    size: float,
    tolerances: tuple[float, float],
    warnings: list[str],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step 4 (end): a free end of a crease that stops just short of *another* stroke ahead of it (within
    :data:`SHORT_OF_BORDER_FRACTION` of the sheet's width, :func:`_sheet_width`, and :data:`NEAR_MISS_CONE_DEG` of
    its direction) is drawn on to where its straight continuation hits the stroke (onto an end of the piece within a
    quarter of the gap, so an end aimed at a crossing reaches the crossing), or to the free end of a stroke of the
    same role and angle that points back at it (one crease drawn as two strokes), with a warning naming it; and a
    piece that runs from a junction a hair past it (as short, to a free end, where its stroke goes on across the
    junction) is removed, as the part of a crease drawn past the border is. Cuts are left as drawn, and are no
    target: the paper between a cut's end and another cut is a bridge (a reviewer's kirigami sheets fell apart).

    Drawn by hand with snapping off, a T-junction stops or overshoots by a few tenths of a millimetre, and a crease
    drawn as two strokes leaves a gap between them. Left so, the crease ended inside the paper (a helper's 200 mm
    sheet, 0.3 mm: strain 0.25 % instead of 0.15 %, fold-angle error 9° instead of 4.4°), silently.

    ``tolerances`` are the merge tolerance and the curves' chord tolerance: an end joined to a curve's chord within
    their sum may lie on the drawn curve itself (its chords stand up to the chord tolerance off it), so that join is
    made without a warning (a helper's ray drawn exactly onto an r = 30 mm circle was told it stopped 0.076 mm
    short)."""
    merge_tolerance, chord_tolerance = tolerances
    assign = pieces.assignment[attrs]
    which, sides = _loose_ends(edges, assign, len(verts))
    if not len(which):
        return verts, edges, attrs
    reach = SHORT_OF_BORDER_FRACTION * _sheet_width(verts, edges, assign, size)
    degree = np.bincount(edges.ravel(), minlength=len(verts))
    length = np.hypot(*(verts[edges[:, 1]] - verts[edges[:, 0]]).T)
    junction = edges[which, 1 - sides]
    # a stub is the end of a stroke drawn on past a crossing (the stroke has another piece at the junction), not a
    # short stroke that starts there
    strokes = int(pieces.polyline.max()) + 1
    at_vertex, at_count = np.unique(edges.ravel() * strokes + np.repeat(pieces.polyline[attrs], 2), return_counts=True)
    same_stroke = at_count[np.searchsorted(at_vertex, junction * strokes + pieces.polyline[attrs[which]])]
    stub = (length[which] <= reach) & (degree[junction] >= 3) & (same_stroke >= 2)
    joined: list[tuple[float, np.ndarray, int]] = []
    mover = _EndMover(verts, edges, attrs, merge_tolerance)
    cone = math.cos(math.radians(NEAR_MISS_CONE_DEG))
    ends_w, ends_side = which[~stub], sides[~stub]
    # the strokes near each end (bounding boxes within reach, from the grid): the work grows with the near pairs
    n_e = len(edges)
    tips, backs = verts[edges[ends_w, ends_side]], verts[edges[ends_w, 1 - ends_side]]
    i, j = _candidate_pairs(
        np.concatenate([verts[edges[:, 0]], tips]), np.concatenate([verts[edges[:, 1]], tips]), reach
    )
    near = (i < n_e) & (j >= n_e)
    near_edge, near_end = i[near], j[near] - n_e
    order = np.argsort(near_end, kind="stable")
    near_edge, near_end = near_edge[order], near_end[order]
    # every end's nearest stroke ahead of it, all ends at once; then the moves, one at a time (a piece split by an
    # earlier move is looked at again with its new halves)
    target_ok = assign != "C"  # not a cut (the paper beyond it is another flap), nor a stub about to go
    target_ok[which[stub]] = False
    keep = (
        target_ok[near_edge]
        & (pieces.polyline[attrs[near_edge]] != pieces.polyline[attrs[ends_w[near_end]]])
        & ~np.any(edges[near_edge] == edges[ends_w[near_end], ends_side[near_end]][:, None], axis=1)
    )
    near_edge, near_end = near_edge[keep], near_end[keep]
    ahead = tips - backs
    ahead /= np.maximum(np.hypot(*ahead.T), 1e-300)[:, None]

    facing_back = math.cos(math.radians(END_TO_END_DEG))

    def nearest_ahead(
        end: np.ndarray, pair: np.ndarray, attr: np.ndarray, a: np.ndarray, b: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """For pairs (end, piece ``pair`` from ``a`` to ``b`` of stroke attribute ``attr``): where the end meets the
        piece, its distance, whether it counts, and whether it is an end-to-end join. The crease drawn on straight
        ahead meets the piece where it hits it (an end aimed at a crossing reaches the crossing); a piece it does
        not hit counts only at a free end of a stroke of the same role and angle that faces it back (a crease drawn
        as two strokes) — never by its nearest point, which pulled the spokes of a star drawn short of its centre
        onto each other's tips (a reviewer's hexagon: not converged in 500 iterations)."""
        tip, d = tips[end], ahead[end]
        r = b - a
        den = _cross(d, r)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = _cross(a - tip, r) / den
            u = _cross(a - tip, d) / den
        hit = (np.abs(den) > 1e-12 * np.hypot(*r.T)) & (t >= 0) & (u >= -1e-9) & (u <= 1 + 1e-9)
        foot = segment_foot(tip, a, b)
        at_a = np.hypot(*(foot - a).T) <= merge_tolerance
        at_b = ~at_a & (np.hypot(*(foot - b).T) <= merge_tolerance)
        free_v = np.where(at_a, pair[:, 0], np.where(at_b, pair[:, 1], -1))
        theirs = foot - np.where(at_a[:, None], b, a)  # the other stroke's direction at that end
        theirs /= np.maximum(np.hypot(*theirs.T), 1e-300)[:, None]
        mine = attrs[ends_w[end]]
        same_kind = (pieces.assignment[attr] == pieces.assignment[mine]) & np.isclose(
            pieces.fold_angle[attr], pieces.fold_angle[mine], rtol=0.0, atol=1e-9, equal_nan=True
        )
        free = (free_v >= 0) & (free_v < len(degree))
        free[free] = degree[free_v[free]] == 1
        end_to_end = ~hit & free & same_kind & (np.einsum("ij,ij->i", theirs, d) <= -facing_back)
        point = np.where(hit[:, None], tip + np.where(hit, t, 0.0)[:, None] * d, foot)
        gap = point - tip
        dist = np.hypot(*gap.T)
        facing = np.einsum("ij,ij->i", gap, d) > cone * dist
        ok = (hit | end_to_end) & facing & (dist > merge_tolerance * (1.0 + 1e-6)) & (dist <= reach)
        return point, dist, ok, end_to_end

    near_pair = edges[near_edge]
    foot, dist, ok, by_end = nearest_ahead(
        near_end, near_pair, attrs[near_edge], verts[near_pair[:, 0]], verts[near_pair[:, 1]]
    )
    order = np.lexsort((dist[ok], by_end[ok], near_end[ok]))  # per end: a hit first, the nearest
    candidate_end = near_end[ok][order]
    first = np.r_[True, candidate_end[1:] != candidate_end[:-1]] if len(candidate_end) else np.zeros(0, bool)
    split: set[int] = set()
    stubs = which[stub]

    def target_ok_now(idx: np.ndarray, stroke_attrs: np.ndarray) -> np.ndarray:
        """:data:`target_ok` for pieces of :meth:`_EndMover.current` (added halves: by their stroke's role)."""
        out = pieces.assignment[stroke_attrs] != "C"
        old = idx < n_e
        out[old] &= target_ok[idx[old]]
        return out

    for c in np.flatnonzero(ok)[order][first]:
        k = int(near_end[c])
        w, side = int(ends_w[k]), int(ends_side[k])
        tip_v, back_v = int(mover.edges[w, side]), int(mover.edges[w, 1 - side])
        if degree[tip_v] != 1:
            continue  # another end was joined to this one
        target, at, gap = int(near_edge[c]), foot[c], float(dist[c])
        if target in split:  # look again, at its halves and every piece added since
            pieces_now = np.r_[target, np.arange(n_e, mover.n_edges())]
            pairs, stroke_attrs = mover.rows(pieces_now)
            own = pieces.polyline[stroke_attrs] == pieces.polyline[attrs[w]]
            end = np.full(len(pieces_now), k)
            f2, d2, ok2, e2 = nearest_ahead(
                end, pairs, stroke_attrs, mover.points(pairs[:, 0]), mover.points(pairs[:, 1])
            )
            ok2 &= ~own & ~np.any(pairs == tip_v, axis=1) & target_ok_now(pieces_now, stroke_attrs)
            if not ok2.any():
                continue
            best = int(np.flatnonzero(ok2)[np.lexsort((d2[ok2], e2[ok2]))[0]])
            target, at, gap = int(pieces_now[best]), f2[best], float(d2[best])
        pts, all_e, _ = mover.current()
        dest_v, dest = mover.destination(target, at, snap=0.25 * gap)
        obstacle = np.ones(len(all_e), dtype=bool)
        obstacle[stubs] = False  # about to be removed
        obstacle[w] = False
        if _join_tangles(pts, all_e, obstacle, (back_v, tip_v), (target, dest_v), dest, merge_tolerance):
            continue  # the end moved there would cross another stroke or touch it: the drawing stays as it is
        n_before = mover.n_edges()
        on_the_curve = bool(pieces.from_curve[mover.rows([target])[1][0]]) and gap <= merge_tolerance + chord_tolerance
        if mover.move(w, side, target, at, snap=0.25 * gap):
            if not on_the_curve:
                joined.append((gap, tips[k], int(attrs[w])))
            if mover.n_edges() > n_before:
                split.add(target)
            degree[tip_v] -= 1
            moved_to = int(mover.edges[w, side])
            degree = np.concatenate([degree, np.zeros(max(0, moved_to + 1 - len(degree)), dtype=degree.dtype)])
            degree[moved_to] += 1 if mover.n_edges() == n_before else 3  # a new vertex: its two halves and this end
    stub_tips = verts[edges[which[stub], sides[stub]]]
    verts, edges, attrs = mover.current()
    trimmed = which[stub]
    if len(trimmed):
        keep = np.ones(len(edges), dtype=bool)
        keep[trimmed] = False
        trimmed_attrs = attrs[trimmed]
        edges, attrs = edges[keep], attrs[keep]
        where = _listed([f"({q[0]:.3f}, {q[1]:.3f})" for q in stub_tips])
        warnings.append(
            f"{len(trimmed)} crease piece(s) drawn a hair past a crossing (at most {reach:.2g} mm, to a free end at "
            f"{where}) were removed, from {_describe_sources(sources, pieces.polyline[trimmed_attrs])}"
        )
    if joined:
        where = _listed([f"{g:.2g} mm at ({q[0]:.3f}, {q[1]:.3f})" for g, q, _ in joined])
        warnings.append(
            f"{len(joined)} crease end(s) stopped just short of another crease and were joined to it ({where}), "
            f"from {_describe_sources(sources, pieces.polyline[[m[2] for m in joined]])}; draw creases to meet, or "
            f"end them more than {reach:.2g} mm away"
        )
    return verts, edges, attrs


def discretize(
    curves: list[CreaseCurve],
    *,
    interval: float | None = None,
    tolerance: float | None = None,
    merge_tolerance: float | None = None,
) -> CreasePattern:
    """Discretise crease curves into a planar :class:`CreasePattern` (paper §3.1; see the module docstring).

    ``None`` parameters take the scale-aware defaults (:func:`default_parameters` of :func:`sheet_size`). The
    result's ``sources`` has one entry per curve (``edge_polyline`` indexes it), ``edge_from_curve`` marks pieces
    of non-straight segments, and ``warnings`` lists capped parameters, duplicate segments with different
    assignments, removed outside pieces and open borders.
    """
    return run_to_end(discretize_steps(curves, interval=interval, tolerance=tolerance, merge_tolerance=merge_tolerance))


def discretize_steps(
    curves: list[CreaseCurve],
    *,
    interval: float | None = None,
    tolerance: float | None = None,
    merge_tolerance: float | None = None,
) -> Generator[str, None, CreasePattern]:
    """:func:`discretize` in units: yields the name of each step done (the curves sampled, the planar arrangement,
    …) and returns the pattern. A Blender job runs one unit per slice: the whole discretisation of a 3,000-segment
    pattern takes ~200 ms, each unit under ~80 ms."""
    if not curves:
        raise PatternError("crease pattern: no curves to discretise")
    _check_coordinates(curves)
    warnings: list[str] = []
    interval, tolerance, merge_tolerance = _resolve_parameters(curves, interval, tolerance, merge_tolerance, warnings)
    curves = _close_open_border(curves, merge_tolerance, SHORT_OF_BORDER_FRACTION * sheet_size(curves), warnings)
    sources = [c.source or f"curve {k}" for k, c in enumerate(curves)]
    interval, tolerance = _guard_explosion(curves, interval, tolerance, warnings)
    yield "parameters"
    pieces = _discretise_curves(curves, sources, interval, tolerance, merge_tolerance, warnings)
    yield "curves sampled"
    verts, edges, attrs = _planar_arrangement(pieces, merge_tolerance, sources)
    yield "planar arrangement"
    edges, attrs = _remove_duplicates(edges, attrs, pieces, sources, warnings)
    size = sheet_size(curves)
    left_short: list[np.ndarray] = []
    verts, edges, attrs = _clip_to_border(
        verts, edges, attrs, pieces, sources, size, (merge_tolerance, tolerance), warnings, left_short
    )
    verts, edges, attrs = _join_near_misses(
        verts, edges, attrs, pieces, sources, size, (merge_tolerance, tolerance), warnings
    )
    _warn_left_short(verts, edges, pieces.assignment[attrs], left_short, warnings)
    # an end moved onto the border, or onto another stroke, can lay its last piece along a piece already there
    edges, attrs = _remove_duplicates(edges, attrs, pieces, sources, warnings)
    yield "clipped to the border"
    edges, attrs, _ = _drop_samples_beside_junctions(verts, edges, attrs, pieces, interval, tolerance)  # step 5
    # curves drawn as polylines are curves too (the ruling swaps score only curve pieces); a stroke with a Bézier or
    # an arc in it says itself which of its pieces are straight
    assignment, angle = pieces.assignment[attrs], pieces.fold_angle[attrs]
    polyline_stroke = np.array([all(seg.is_straight for seg in c.segments) for c in curves], dtype=bool)
    drawn_polyline = polyline_stroke[pieces.polyline[attrs]]
    from_curve = pieces.from_curve[attrs] | (
        flattened_curves(verts, edges, assignment, angle, tolerance) & drawn_polyline
    )
    # a polyline sampled far finer than the interval is thinned to the paper's sampling (drawn vertices kept), unless
    # it is a curve we discretised and wrote ourselves (our SVG export's polylines: they read back as written)
    sampled = np.array([c.sampled for c in curves], dtype=bool)[pieces.polyline[attrs]]
    thin = drawn_polyline & (assignment != "F") & ~sampled
    kept, chords, source = thin_dense_polylines(verts, edges, assignment, angle, thin, interval, tolerance)
    if len(chords):
        edges = np.concatenate([edges[kept], chords])
        attrs = np.concatenate([attrs[kept], attrs[source]])
        from_curve = np.concatenate([from_curve[kept], from_curve[source]])
        assignment = pieces.assignment[attrs]
    # step 6: border and cut pieces drawn straight, between junctions, split evenly (a flattened curve's too: its
    # chords can be far longer than the interval, and the rulings need border vertices to end at; a cut is two
    # borders once cut open, and a lone slit needs a vertex inside to open at all)
    # (not our SVG export's polylines: they are the meshed pattern's pieces, read back as written; a chord a curve's
    # junction lengthened to 10.001 mm at a 10 mm interval was split again and the file meshed otherwise)
    sampled = np.array([c.sampled for c in curves], dtype=bool)[pieces.polyline[attrs]]
    drawn_straight = np.isin(assignment, ("B", "C")) & ~pieces.from_curve[attrs] & ~sampled
    least = np.where(_lone_slits(edges, assignment), 2, 1)
    verts, edges, kept = _subdivide_straight(verts, edges, np.arange(len(edges)), drawn_straight, interval, least)
    attrs, from_curve = attrs[kept], from_curve[kept]

    # drop stray vertices, renumber
    used = np.unique(edges)
    remap = np.full(len(verts), -1, np.int64)
    remap[used] = np.arange(len(used))
    pattern = CreasePattern(
        vertices=verts[used],
        edges=remap[edges],
        assignments=pieces.assignment[attrs],
        fold_angles=pieces.fold_angle[attrs],
        edge_polyline=pieces.polyline[attrs],
        edge_from_curve=from_curve,
        sources=sources,
        warnings=warnings,
        interval=interval,
    )
    pattern.validate()
    return pattern
