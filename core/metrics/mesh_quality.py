"""Triangle shape of a mesh against what its crease pattern forces (issue 12: no sliver the solver can squash flat).

A triangle with a corner near 0° can be squashed to a line by the solver, where the face-angle energy has a kink; the
stalls of issue 12 came with corners down to 0.04°. Some small corners are forced by the drawing itself (two creases
meeting at 1°, a 0.17 mm facet beside a 76 mm crease), so a mesh is judged against the pattern's own bound:

* :func:`forced_smallest_corner`: the smallest corner *any* triangulation of the pattern's segments (with no added
  vertices but those the triangulation stage puts on long straight creases beside needles, :mod:`..mesh.needles`)
  must have. The constrained Delaunay triangulation maximises the smallest angle over all constrained
  triangulations of the same vertices and segments (Lee & Lin 1986), so the bound is the CDT's smallest corner over
  the paper's triangles, exactly;
* :func:`smallest_segment_gap`: the smallest angle between two segments meeting at a vertex, a corner no
  triangulation can avoid (an upper bound of the former, shown to say *why* a pattern forces a small corner);
* :func:`corner_angles`, :func:`corner_summary`: the mesh's own corners, the smallest and the count under
  :data:`SLIVER_DEG`.
"""

from __future__ import annotations

import numpy as np

from ..mesh.fold_mesh import FoldMesh, corner_angles, segments_by_angle
from ..mesh.needles import NEEDLE_DEG, split_needle_creases
from ..pattern.model import CreasePattern

SLIVER_DEG = NEEDLE_DEG
"""Corners under this many degrees (1°) are counted as slivers (the issue's count: 110 such corners stalled a
solve); the triangulation splits long straight creases beside such corners (:mod:`..mesh.needles`)."""


def forced_smallest_corner(pattern: CreasePattern, backend: str = "auto") -> float:
    """The smallest corner (degrees) every triangulation of ``pattern``'s segments, as the triangulation stage splits
    them, without added vertices has: the constrained Delaunay triangulation's smallest corner over the paper (see
    the module docstring)."""
    pt = split_needle_creases(pattern, backend)[1]
    return float(corner_angles(pt.vertices, pt.triangles).min())


def smallest_segment_gap(pattern: CreasePattern) -> float:
    """The smallest angle (degrees) between two consecutive segments around any vertex of ``pattern`` (180° when no
    vertex has two segments); the angle may lie outside the paper, so it bounds the forced corner only from above."""
    v = pattern.vertices
    ends, ang, _ = segments_by_angle(v, pattern.edges)
    deg = np.bincount(ends[:, 0], minlength=len(v))
    first = np.r_[True, ends[1:, 0] != ends[:-1, 0]]
    start = np.flatnonzero(first)
    nxt = np.arange(len(ang)) + 1
    last = np.r_[start[1:], len(ang)] - 1
    nxt[last] = start  # wrap around each vertex
    gap = np.mod(ang[nxt] - ang, 2.0 * np.pi)
    several = deg[ends[:, 0]] >= 2
    return float(np.degrees(gap[several].min())) if several.any() else 180.0


def corner_summary(mesh: FoldMesh, forced: float | None = None) -> dict[str, float]:
    """The flat mesh's smallest corner and number of corners under :data:`SLIVER_DEG`, with the pattern's forced
    bound when given (``forced_smallest_corner_deg``)."""
    c = corner_angles(mesh.vertices, mesh.triangles)
    out = {
        "smallest_corner_deg": float(c.min()) if c.size else float("nan"),
        "corners_below_1deg": float(np.count_nonzero(c < SLIVER_DEG)),
    }
    if forced is not None:
        out["forced_smallest_corner_deg"] = float(forced)
    return out
