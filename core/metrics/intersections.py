"""Self-intersection of a folded sheet: which pairs of non-adjacent triangles pass through each other.

The paper "does not address self-penetration"; the solver does not model contact either. A designer still needs to
know when paper passes through paper (a render shows it), so after every solve the report counts the triangles that
cross another one (``self_intersecting_faces``) and the viewport colours them. Detection only, no contact force.

Two phases, both vectorised with numpy:

* **broad phase** — a uniform grid over the triangles' axis-aligned bounding boxes: each triangle is entered in every
  cell its box covers, the pairs sharing a cell (deduplicated) whose boxes overlap are the candidates. The cell size
  is the smallest multiple of the median box size that enters the triangles in a few cells each on average, so
  long ruling triangles do not fill the grid and small facets do not share crowded cells;
* **narrow phase** — Möller's triangle–triangle test (J. Graphics Tools 2(2), 1997): the signed distances of each
  triangle's corners to the other's plane, then the two triangles' intervals on the planes' intersection line.

Pairs that share a vertex are neighbours in the sheet (they meet along an edge or at a corner by construction) and
are never reported. Contact is not penetration: triangles that only touch (a corner on a face, an edge on an edge)
or lie in the same plane (stacked layers of a flat fold) are not counted; the tolerance is ``1e-6`` of the folded
bounding-box diagonal (the box on the sheet's principal axes: the test turns the sheet onto them first).
"""

from __future__ import annotations

from collections.abc import Generator, Iterator

import numpy as np

from .. import run_to_end

REL_TOLERANCE = 1e-6
"""Distances below this fraction of the folded bounding-box diagonal count as touching, not crossing."""

CELL_FACTORS = (1.0, 2.0, 4.0, 8.0, 16.0)
"""Grid cell sizes tried in turn, as multiples of the median triangle box size."""

CELL_ENTRIES_PER_TRIANGLE = 4
"""The first cell size that enters triangles in at most this many cells on average is used."""

CHUNK_PAIRS = 2_000_000
"""Raw same-cell pairs handled at once (bounds the memory of heavily layered folds)."""

UNIT_PAIRS = 250_000
"""Raw same-cell pairs per unit of :func:`intersecting_faces_steps` (a Blender job's slice runs one): a 4,128-face
circular pleat folded to 180°, crossing itself almost everywhere, took 147–154 ms in one call (a designer session)."""


def _cells(lo: np.ndarray, hi: np.ndarray, origin: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """First and last grid cell index ``(t, 3)`` covered by each box at cell size ``h``."""
    return np.floor((lo - origin) / h).astype(np.int64), np.floor((hi - origin) / h).astype(np.int64)


def _pairs_in_cells(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Candidate pairs ``(k, 2)`` (``i < j``, unique) of triangles whose boxes ``lo``/``hi`` ``(t, 3)`` overlap."""
    chunks = list(_candidate_chunks(lo, hi))
    return np.concatenate(chunks) if chunks else np.zeros((0, 2), dtype=np.int64)


def _candidate_chunks(lo: np.ndarray, hi: np.ndarray, chunk_pairs: int = CHUNK_PAIRS) -> Iterator[np.ndarray]:
    """:func:`_pairs_in_cells` in chunks of at most about ``chunk_pairs`` raw pairs each, so memory stays bounded
    when many triangles share cells (the stacked layers of a flat fold overlap pairwise)."""
    t = len(lo)
    if t < 2:
        return
    origin = lo.min(axis=0)
    size = float(np.median(np.max(hi - lo, axis=1)))
    if not size > 0:
        extent = float(np.max(hi.max(axis=0) - origin))
        size = extent / t ** (1.0 / 3.0) if extent > 0 else 1.0
    # the smallest cell (fewest candidates per cell) that enters triangles in few cells on average
    for factor in CELL_FACTORS:
        h = size * factor
        c0, c1 = _cells(lo, hi, origin, h)
        span = c1 - c0 + 1
        count = np.prod(span, axis=1)
        if count.sum() <= CELL_ENTRIES_PER_TRIANGLE * t:
            break
    entries = int(count.sum())
    tri = np.repeat(np.arange(t), count)
    local = np.arange(entries) - np.repeat(np.cumsum(count) - count, count)
    sx, sy = span[tri, 0], span[tri, 1]
    cell = c0[tri] + np.column_stack([local % sx, (local // sx) % sy, local // (sx * sy)])
    dims = np.max(c1, axis=0) + 1
    key = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
    order = np.argsort(key, kind="stable")
    key, tri = key[order], tri[order]
    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    sizes = np.diff(np.r_[starts, len(key)])
    # every entry pairs with the entries after it in its cell
    group_end = np.repeat(starts + sizes, sizes)
    position = np.arange(len(tri))
    partners = group_end - position - 1
    # a pair whose boxes share several cells is kept once: in the cell holding the low corner of the boxes' overlap
    # (floor is monotonic, so that cell is the componentwise max of the boxes' first cells). Gathers are done per
    # coordinate column: numpy gathers 1-D arrays several times faster than rows of a 2-D one.
    cx, cy, cz = (np.ascontiguousarray(c0[:, k]) for k in range(3))
    los = [np.ascontiguousarray(lo[:, k]) for k in range(3)]
    his = [np.ascontiguousarray(hi[:, k]) for k in range(3)]
    ends = np.cumsum(partners)
    begin = 0
    while begin < len(position):
        stop = int(np.searchsorted(ends, (ends[begin - 1] if begin else 0) + chunk_pairs, side="right"))
        stop = max(stop, begin + 1)
        part = partners[begin:stop]
        total = int(part.sum())
        if total:
            first = np.repeat(position[begin:stop], part)
            second = first + 1 + np.arange(total) - np.repeat(np.cumsum(part) - part, part)
            a, b = tri[first], tri[second]
            ref = (np.maximum(cx[a], cx[b]) * dims[1] + np.maximum(cy[a], cy[b])) * dims[2] + np.maximum(cz[a], cz[b])
            once = ref == key[first]
            a, b = a[once], b[once]
            for k in range(3):
                overlap = (los[k][a] <= his[k][b]) & (los[k][b] <= his[k][a])
                a, b = a[overlap], b[overlap]
            yield np.column_stack([np.minimum(a, b), np.maximum(a, b)])
        begin = stop


def _interval(d: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Interval ``(lo, hi)`` that a triangle covers on the planes' intersection line.

    ``d`` ``(k, 3)``: its corners' signed distances to the other plane (zeros snapped); ``p`` ``(k, 3)``: the
    corners projected on the line. The interval spans the points where edges cross the plane and corners in it."""
    values = []
    masks = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        di, dj = d[:, i], d[:, j]
        cross = di * dj < 0
        with np.errstate(invalid="ignore", divide="ignore"):
            s = np.where(cross, di / np.where(cross, di - dj, 1.0), 0.0)
        values.append(p[:, i] + (p[:, j] - p[:, i]) * s)
        masks.append(cross)
    for i in range(3):
        values.append(p[:, i])
        masks.append(d[:, i] == 0)
    v = np.stack(values, axis=1)
    m = np.stack(masks, axis=1)
    return np.where(m, v, np.inf).min(axis=1), np.where(m, v, -np.inf).max(axis=1)


def _unit_normals(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals ``(t, 3)`` of triangles given as corners ``(t, 3, 3)``, and a mask of the non-degenerate ones."""
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.sqrt(np.einsum("kj,kj->k", n, n))
    ok = length > 0  # a degenerate (zero-area) triangle crosses nothing
    return n / np.where(ok, length, 1.0)[:, None], ok


class _Columns:
    """Per-coordinate contiguous columns of the triangles, positions and planes: numpy gathers 1-D arrays several
    times faster than rows of a 2-D one, and the candidate pairs are many."""

    def __init__(self, x: np.ndarray, tris: np.ndarray, normals: np.ndarray):
        self.corner = [np.ascontiguousarray(tris[:, c]) for c in range(3)]
        self.x = [np.ascontiguousarray(x[:, k]) for k in range(3)]
        self.n = [np.ascontiguousarray(normals[:, k]) for k in range(3)]
        self.offset = np.einsum("tj,tj->t", normals, x[tris[:, 0]])

    def neighbours(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Pairs sharing a vertex."""
        out = np.zeros(len(a), dtype=bool)
        for i in range(3):
            ci = self.corner[i][a]
            for j in range(3):
                out |= ci == self.corner[j][b]
        return out

    def straddles(self, a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
        """Pairs whose triangle ``b`` has corners strictly on both sides of triangle ``a``'s plane (``|d| ≤ tol``
        counts as on it): a corner or an edge lying in the other plane with the rest on one side is contact, and so
        are coplanar triangles."""
        n0, n1, n2, off = self.n[0][a], self.n[1][a], self.n[2][a], self.offset[a]
        below = np.zeros(len(a), dtype=bool)
        above = np.zeros(len(a), dtype=bool)
        for c in range(3):
            v = self.corner[c][b]
            d = n0 * self.x[0][v] + n1 * self.x[1][v] + n2 * self.x[2][v] - off
            below |= d < -tol
            above |= d > tol
        return below & above


def _crossing(x: np.ndarray, tri_a: np.ndarray, tri_b: np.ndarray, na: np.ndarray, nb: np.ndarray, tol: float):
    """Möller's interval test on pairs that straddle each other's planes: mask of the pairs that cross.

    ``tri_a``/``tri_b`` ``(k, 3)`` corner indices, ``na``/``nb`` ``(k, 3)`` their unit normals."""
    A = x[tri_a]  # (k, 3 corners, 3)
    B = x[tri_b]
    db = np.einsum("kj,kcj->kc", na, B - A[:, :1])  # B's corners against A's plane
    da = np.einsum("kj,kcj->kc", nb, A - B[:, :1])
    da = np.where(np.abs(da) <= tol, 0.0, da)
    db = np.where(np.abs(db) <= tol, 0.0, db)
    line = np.cross(na, nb)
    ln = np.sqrt(np.einsum("kj,kj->k", line, line))
    good = ln > 1e-12
    line = line / np.where(good, ln, 1.0)[:, None]
    # project relative to a corner: for nearly parallel planes the line direction is only accurate to
    # round-off / sin(angle), and the error grows with the distance from the projection's origin
    pa = np.einsum("kj,kcj->kc", line, A - A[:, :1])
    pb = np.einsum("kj,kcj->kc", line, B - A[:, :1])
    a0, a1 = _interval(da, pa)
    b0, b1 = _interval(db, pb)
    return good & (np.minimum(a1, b1) - np.maximum(a0, b0) > tol)


def _principal_frame(x: np.ndarray) -> np.ndarray:
    """``x`` centred and turned onto its principal axes (a rigid motion: crossings do not change). The grid's boxes
    are axis-aligned, so a sheet tilted in space gave loose boxes and more candidate pairs: a coiled circular pleat
    standing on edge took 143 ms against 42 ms lying flat."""
    x = x - x.mean(axis=0)
    _, axes = np.linalg.eigh(x.T @ x)
    return x @ axes


def intersecting_pairs(positions: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Pairs ``(k, 2)`` (``i < j``) of triangles that pass through each other, neighbours (a shared vertex) excluded.

    ``positions`` ``(n, 3)`` (any length unit), ``triangles`` ``(t, 3)`` vertex indices."""
    return run_to_end(intersecting_pairs_steps(positions, triangles, CHUNK_PAIRS))


def intersecting_pairs_steps(
    positions: np.ndarray, triangles: np.ndarray, chunk_pairs: int = UNIT_PAIRS
) -> Generator[None, None, np.ndarray]:
    """:func:`intersecting_pairs` in units of ``chunk_pairs`` raw candidate pairs (one chunk of the broad phase and
    its narrow phase per unit)."""
    x = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    tris = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(tris) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    if not np.all(np.isfinite(x[tris])):
        raise ValueError("positions must be finite to test for self-intersection")
    x = _principal_frame(x)
    corners = x[tris]
    diagonal = float(np.linalg.norm(corners.max(axis=(0, 1)) - corners.min(axis=(0, 1))))
    tol = REL_TOLERANCE * diagonal
    normals, flat = _unit_normals(corners)
    cols = _Columns(x, tris, normals)
    found = [np.zeros((0, 2), dtype=np.int64)]
    for pairs in _candidate_chunks(corners.min(axis=1) - tol, corners.max(axis=1) + tol, chunk_pairs):
        if len(found) > 1:
            yield
        a, b = pairs[:, 0], pairs[:, 1]
        # staged: most candidates (neighbours, pairs a plane separates) leave after the cheap tests
        keep = ~cols.neighbours(a, b) & flat[a] & flat[b]
        a, b = a[keep], b[keep]
        keep = cols.straddles(a, b, tol)
        a, b = a[keep], b[keep]
        keep = cols.straddles(b, a, tol)
        a, b = a[keep], b[keep]
        keep = _crossing(x, tris[a], tris[b], normals[a], normals[b], tol)
        found.append(np.column_stack([a[keep], b[keep]]))
    return np.concatenate(found)


def intersecting_faces(positions: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Mask ``(t,)`` of the triangles that cross at least one non-adjacent triangle."""
    return run_to_end(intersecting_faces_steps(positions, triangles, CHUNK_PAIRS))


def intersecting_faces_steps(
    positions: np.ndarray, triangles: np.ndarray, chunk_pairs: int = UNIT_PAIRS
) -> Generator[None, None, np.ndarray]:
    """:func:`intersecting_faces` in units (:func:`intersecting_pairs_steps`)."""
    tris = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    mask = np.zeros(len(tris), dtype=bool)
    mask[(yield from intersecting_pairs_steps(positions, tris, chunk_pairs)).reshape(-1)] = True
    return mask


def count_intersecting_faces(positions: np.ndarray, triangles: np.ndarray) -> int:
    """Number of triangles that cross at least one non-adjacent triangle (the report's ``self_intersecting_faces``)."""
    return int(np.count_nonzero(intersecting_faces(positions, triangles)))
