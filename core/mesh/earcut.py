"""Plain ear clipping of a simple polygon (Origami Simulator's default triangulation, for the ``earcut`` baseline).

Origami Simulator triangulates each crease-pattern face with mapbox's earcut. This is the textbook algorithm
(no hole bridging, no z-order hashing; vectorised, see :func:`ear_clip`): walk the polygon, clip the first *ear*
(a strictly convex corner whose triangle contains no other polygon vertex), repeat. Its long fans at one vertex
are what the paper's CDT avoids.
"""

from __future__ import annotations

import numpy as np


def _orient(p: np.ndarray, q: np.ndarray, r: np.ndarray) -> float:
    return float((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]))


def _orient_rows(p: np.ndarray, q: np.ndarray, r: np.ndarray) -> np.ndarray:
    """:func:`_orient` with ``r`` (or all three) given as rows: the same floating-point operations per row."""
    return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])


def ear_clip(points: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Triangles ``(n − 2, 3)`` (indices into ``points``, CCW) of the simple CCW polygon ``loop``.

    Collinear corners (discretised straight borders) are not ears; they are clipped last, when only degenerate
    corners remain, by taking the corner with the largest area (keeps every triangle non-degenerate when possible).

    The walk is the textbook one (after clipping, continue from the clipped corner's position; the first corner
    that is an ear is clipped), with two accelerations that do not change which corner is clipped: the "is any
    other vertex inside this corner's triangle" test runs over all remaining vertices at once in numpy, and a
    corner found blocked remembers its blocking vertex, so while its triangle is unchanged and the blocker is
    still in the polygon it is skipped in O(1) (a point inside a fixed triangle stays inside). Each clip then
    costs O(n) numpy work plus O(n) cheap skips: O(n²) in all, instead of the O(n³) Python loops.
    """
    idx = [int(i) for i in loop]
    n = len(idx)
    if n < 3:
        raise ValueError(f"ear_clip: a polygon needs at least 3 vertices, got {n}")
    pts = np.asarray(points, dtype=float)
    span = pts[idx].max(axis=0) - pts[idx].min(axis=0)
    eps = 1e-12 * float(span @ span)
    out: list[tuple[int, int, int]] = []
    poly = idx[:]
    P = pts[poly]  # coordinates of the remaining polygon, kept in step with poly
    xy = {v: pts[v] for v in poly}
    alive = set(poly)
    blocked: dict[int, tuple[int, int, int]] = {}  # corner → (prev, next, a vertex inside its triangle)
    i = 0
    guard = 0
    while len(poly) > 3:
        m = len(poly)
        found = False
        for step in range(m):
            k = (i + step) % m
            a, b, c = poly[k - 1], poly[k], poly[(k + 1) % m]
            pa, pb, pc = xy[a], xy[b], xy[c]
            if _orient(pa, pb, pc) <= eps:
                continue
            memo = blocked.get(b)
            if memo is not None and memo[0] == a and memo[1] == c and memo[2] in alive:
                continue
            o1 = _orient_rows(pa, pb, P) >= -eps
            o2 = _orient_rows(pb, pc, P) >= -eps
            o3 = _orient_rows(pc, pa, P) >= -eps
            hit = o1 & o2 & o3
            hit &= ~(np.all(P == pa, axis=1) | np.all(P == pb, axis=1) | np.all(P == pc, axis=1))
            hit[[k - 1, k, (k + 1) % m]] = False
            if hit.any():
                blocked[b] = (a, c, poly[int(np.argmax(hit))])
                continue
            out.append((a, b, c))
            poly.pop(k)
            P = np.delete(P, k, axis=0)
            alive.discard(b)
            i = k % len(poly)
            found = True
            break
        if not found:  # only degenerate corners left: clip the fattest one
            areas = _orient_rows(np.roll(P, 1, axis=0), P, np.roll(P, -1, axis=0))
            k = int(np.argmax(areas))
            b = poly[k]
            out.append((poly[k - 1], b, poly[(k + 1) % m]))
            poly.pop(k)
            P = np.delete(P, k, axis=0)
            alive.discard(b)
            i = k % len(poly)
        guard += 1
        if guard > 4 * n:  # pragma: no cover - each pass removes one vertex
            raise RuntimeError("ear_clip did not terminate")
    out.append((poly[0], poly[1], poly[2]))
    return np.asarray(out, dtype=np.int64)
