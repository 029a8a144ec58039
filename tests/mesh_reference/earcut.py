"""Plain ear clipping of a simple polygon (Origami Simulator's default triangulation, for the ``earcut`` baseline).

Origami Simulator triangulates each crease-pattern face with mapbox's earcut. This is the textbook algorithm
(no hole bridging, no z-order hashing): walk the polygon, clip the first *ear* (a strictly convex corner whose
triangle contains no other polygon vertex), repeat. Its long fans at one vertex are what the paper's CDT avoids.
"""

from __future__ import annotations

import numpy as np


def _orient(p: np.ndarray, q: np.ndarray, r: np.ndarray) -> float:
    return float((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]))


def ear_clip(points: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Triangles ``(n − 2, 3)`` (indices into ``points``, CCW) of the simple CCW polygon ``loop``.

    Collinear corners (discretised straight borders) are not ears; they are clipped last, when only degenerate
    corners remain, by taking the corner with the largest area (keeps every triangle non-degenerate when possible).
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
    i = 0
    guard = 0
    while len(poly) > 3:
        m = len(poly)
        found = False
        for step in range(m):
            k = (i + step) % m
            a, b, c = poly[k - 1], poly[k], poly[(k + 1) % m]
            pa, pb, pc = pts[a], pts[b], pts[c]
            if _orient(pa, pb, pc) <= eps:
                continue
            inside = False
            for v in poly:
                if (
                    v in (a, b, c)
                    or np.array_equal(pts[v], pa)
                    or np.array_equal(pts[v], pb)
                    or np.array_equal(pts[v], pc)
                ):
                    continue
                pv = pts[v]
                if _orient(pa, pb, pv) >= -eps and _orient(pb, pc, pv) >= -eps and _orient(pc, pa, pv) >= -eps:
                    inside = True
                    break
            if inside:
                continue
            out.append((a, b, c))
            poly.pop(k)
            i = k % len(poly)
            found = True
            break
        if not found:  # only degenerate corners left: clip the fattest one
            areas = [_orient(pts[poly[k - 1]], pts[poly[k]], pts[poly[(k + 1) % m]]) for k in range(m)]
            k = int(np.argmax(areas))
            out.append((poly[k - 1], poly[k], poly[(k + 1) % m]))
            poly.pop(k)
            i = k % len(poly)
        guard += 1
        if guard > 4 * n:  # pragma: no cover - each pass removes one vertex
            raise RuntimeError("ear_clip did not terminate")
    out.append((poly[0], poly[1], poly[2]))
    return np.asarray(out, dtype=np.int64)
