"""Long straight creases split where the triangulation would fan needles off them (paper §3.2, issue 12 "no kinks").

The paper's triangulation adds no interior points, and §3.1 samples only curves: a straight crease stays one
segment from junction to junction, however long. Where a curve runs close to such a crease (a sine crossing
straight pleats at a shallow angle, a curve ending just beside a long valley), the constrained Delaunay
triangulation has no vertex on the crease to connect the curve's samples to but its far end points, and fans
needles 100 mm long with corners of 0.03° (``tests/data/sine_across_pleats.svg``), the triangles the solver squashes
flat. They are not forced by the drawing: with vertices along the crease the same drawing meshes with corners no
smaller than the angles its creases meet at.

So, as the border is (§3.1), a straight crease is split into ⌈length / interval⌉ equal pieces, but only where it
bounds a needle's corner (:func:`needle_creases`): elsewhere (every fixture but ``huffmanTower``) the mesh is the
paper's, vertex for vertex. Splitting every straight crease was measured and not kept: the extra
vertices score in no ruling estimate, and the mean warp rose on patterns that had no needle (``huffmanTower`` 2.7°
→ 11.1°, docs/meshes.md). The new vertices lie on the crease, so its pieces fold as one crease and the sheet keeps
its outline; the triangulation is then made again, until no crease is split (:data:`MAX_ROUNDS`).
"""

from __future__ import annotations

import math
from collections.abc import Generator

import numpy as np

from .. import run_to_end
from ..pattern.discretize import pattern_interval, subdivide_edges
from ..pattern.model import CreasePattern
from .fold_mesh import corner_angles
from .triangulate import PlanarTriangulation, constrained_triangulation

NEEDLE_DEG = 1.0
"""A triangle with a corner under this is a needle (the corners the quality metrics count as slivers,
``metrics.mesh_quality.SLIVER_DEG``)."""

MAX_ROUNDS = 64
"""Triangulations made at most: the first, and one after each round of splits. A split can leave a needle beside
the next crease (24 parallel pleats, the middle ones split first, fan to their neighbours' ends), so rounds go on
while some crease is split; each round splits at least one crease, so they end, and the drawings measured needed
one to three."""


def needle_creases(pattern: CreasePattern, pt: PlanarTriangulation, interval: float) -> np.ndarray:
    """Mask of ``pattern``'s edges to split: straight creases (not border, not cut, not a curve piece) longer than
    ``interval`` that bound a needle's sector. A needle is a triangle of ``pt`` with a corner under
    :data:`NEEDLE_DEG` between two sides that are not both segments (a corner between two segments is the drawing's
    own); its sector is the angle around the corner's vertex between the segments on either side of it, and a long
    straight crease bounding it gives the fan no vertex nearer than the crease's far end."""
    e = pattern.edges
    length = np.hypot(*(pattern.vertices[e[:, 1]] - pattern.vertices[e[:, 0]]).T)
    eligible = ~np.isin(pattern.assignments, ("B", "C")) & ~pattern.edge_from_curve & (length > interval * (1 + 1e-9))
    out = np.zeros(len(e), dtype=bool)
    if not eligible.any() or len(pt.triangles) == 0:
        return out
    tris, pts = pt.triangles, pt.vertices
    corners = corner_angles(pts, tris)
    t_small, k_small = np.nonzero(corners < NEEDLE_DEG)
    if len(t_small) == 0:
        return out
    seg = np.array(list(pt.segment_of), dtype=np.int64).reshape(-1, 2)
    seg_edge = np.fromiter(pt.segment_of.values(), dtype=np.int64, count=len(seg))
    ends = np.concatenate([seg, seg[:, ::-1]])  # (w, other end) both ways
    ends_edge = np.concatenate([seg_edge, seg_edge])
    d = pts[ends[:, 1]] - pts[ends[:, 0]]
    angle = np.arctan2(d[:, 1], d[:, 0])
    order = np.lexsort((angle, ends[:, 0]))
    ends, ends_edge, angle = ends[order], ends_edge[order], angle[order]
    first = np.searchsorted(ends[:, 0], np.arange(len(pts)), "left")
    last = np.searchsorted(ends[:, 0], np.arange(len(pts)), "right")
    for t, k in zip(t_small.tolist(), k_small.tolist(), strict=True):
        w, x, y = int(tris[t, k]), int(tris[t, (k + 1) % 3]), int(tris[t, (k + 2) % 3])
        if (min(w, x), max(w, x)) in pt.segment_of and (min(w, y), max(w, y)) in pt.segment_of:
            continue
        lo, hi = first[w], last[w]
        if lo == hi:
            continue
        mid = pts[x] + pts[y] - 2.0 * pts[w]  # the corner's bisector (CCW triangle: x then y)
        phi = np.arctan2(mid[1], mid[0])
        gap = np.mod(angle[lo:hi] - phi, 2.0 * np.pi)
        for side in (int(np.argmin(gap)), int(np.argmax(gap))):  # the first segment CCW, the first CW
            edge = int(ends_edge[lo + side])
            out[edge] |= bool(eligible[edge])
    return out


def split_needle_creases(pattern: CreasePattern, backend: str = "auto") -> tuple[CreasePattern, PlanarTriangulation]:
    """``pattern`` with its long straight creases split where they fan needles (module docstring), and its
    constrained triangulation; ``pattern`` itself and its triangulation where none does."""
    return run_to_end(split_needle_creases_steps(pattern, backend))


def split_needle_creases_steps(
    pattern: CreasePattern, backend: str = "auto"
) -> Generator[str, None, tuple[CreasePattern, PlanarTriangulation]]:
    """:func:`split_needle_creases` in units, one triangulation each (a Blender job runs one per slice)."""
    pt = constrained_triangulation(pattern, backend)
    interval = pattern_interval(pattern)
    for _ in range(MAX_ROUNDS - 1):
        if not (interval > 0 and math.isfinite(interval)):  # an infinite interval keeps every crease whole
            break
        which = needle_creases(pattern, pt, interval)
        if not which.any():
            break
        yield "triangulated"
        pattern = subdivide_edges(pattern, which, interval)
        pt = constrained_triangulation(pattern, backend)
    return pattern, pt
