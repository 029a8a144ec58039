"""Long straight creases split where the triangulation would fan needles off them (paper §3.2, issue 12 "no kinks").

The paper's triangulation adds no interior points, and §3.1 samples only curves: a straight crease stays one
segment from junction to junction, however long. Where a curve runs close to such a crease (a sine crossing
straight pleats at a shallow angle) or a crease stops just beside it, the constrained Delaunay triangulation has no
vertex on the crease to connect to but its far end points, and fans needles 100 mm long with corners of 0.03°
(``tests/data/sine_across_pleats.svg``), the triangles the solver squashes flat. They are not forced by the drawing:
with vertices along the crease the same drawing meshes with far larger corners.

So, as the border is (§3.1), such a crease is split into ⌈length / interval⌉ equal pieces (:func:`needle_creases`):

* a **needle** is a triangle with a corner under :data:`NEEDLE_DEG` that is not the angle between two segments (that
  one is the drawing's own);
* the creases split are the long straight creases bounding the needle's corner, and those parallel to them across
  thin strips beside them (:func:`_across_strips`: a strip split on one side only fans from the other side's ends);
  a straight cut counts as a crease: it is meshed as one and only then cut open (``triangulate.split_cuts``);
* the pattern is then triangulated again, until no crease is split (:data:`MAX_ROUNDS`), within the
  discretisation's segment budget (:func:`_within_budget`).

Elsewhere (every fixture but ``huffmanTower``) the mesh is the paper's, vertex for vertex. Splitting every straight
crease was measured and not kept: the extra vertices score in no ruling estimate, and the mean warp rose on patterns
that had no needle (``huffmanTower`` 2.7° → 11.1°, docs/meshes.md). The new vertices lie on the crease, so its
pieces fold as one crease and the sheet keeps its outline.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from dataclasses import replace

import numpy as np

from .. import run_to_end
from ..pattern.discretize import MAX_SEGMENTS, pattern_interval, subdivide_edges
from ..pattern.model import CreasePattern
from .fold_mesh import corner_angles, segments_by_angle
from .triangulate import PlanarTriangulation, constrained_triangulation

NEEDLE_DEG = 1.0
"""A triangle with a corner under this is a needle (the corners the quality metrics count as slivers,
``metrics.mesh_quality.SLIVER_DEG``)."""

STRIP_DEG = 10.0
"""Creases on one face within this angle of parallel to a split one, and as thin a strip from it, are split with it
(:func:`_across_strips`)."""

MAX_ROUNDS = 64
"""Triangulations made at most: the first, and one after each round of splits (each splits at least one crease).
With the splits carried across strips, every drawing measured needed one round; a warning says when needles are
left at the cap."""


def needle_creases(pattern: CreasePattern, pt: PlanarTriangulation, interval: float) -> np.ndarray:
    """Mask of ``pattern``'s edges to split: straight creases and cuts (not border, not a curve piece) longer than
    ``interval`` that bound a needle's sector, and those parallel to them across thin strips (:func:`_across_strips`).
    A needle is a triangle of ``pt`` with a corner under :data:`NEEDLE_DEG` between two sides that are not both
    segments (a corner between two segments is the drawing's own); its sector is the angle around the corner's
    vertex between the segments on either side of it, and a long straight crease bounding it gives the fan no vertex
    nearer than the crease's far end. Faces of straight creases alone count too: a hypar's trapezoids bend, and kept
    whole its fold missed its angles by 47° (10° split; a review session's drawing)."""
    e = pattern.edges
    length = np.hypot(*(pattern.vertices[e[:, 1]] - pattern.vertices[e[:, 0]]).T)
    eligible = (pattern.assignments != "B") & ~pattern.edge_from_curve & (length > interval * (1 + 1e-9))
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
    ends, angle, row = segments_by_angle(pts, seg)
    ends_edge = seg_edge[row]
    first = np.searchsorted(ends[:, 0], np.arange(len(pts)), "left")
    last = np.searchsorted(ends[:, 0], np.arange(len(pts)), "right")
    for t, k in zip(t_small.tolist(), k_small.tolist(), strict=True):
        w, x, y = int(tris[t, k]), int(tris[t, (k + 1) % 3]), int(tris[t, (k + 2) % 3])
        if (min(w, x), max(w, x)) in pt.segment_of and (min(w, y), max(w, y)) in pt.segment_of:
            continue
        lo, hi = first[w], last[w]  # w is on a segment: every triangulation vertex is
        mid = pts[x] + pts[y] - 2.0 * pts[w]  # towards the opposite side's midpoint, inside the corner
        phi = np.arctan2(mid[1], mid[0])
        gap = np.mod(angle[lo:hi] - phi, 2.0 * np.pi)
        for side in (int(np.argmin(gap)), int(np.argmax(gap))):  # the first segment CCW, the first CW
            edge = int(ends_edge[lo + side])
            out[edge] |= bool(eligible[edge])
    return _across_strips(pattern, pt, out, eligible)


def _across_strips(
    pattern: CreasePattern, pt: PlanarTriangulation, marked: np.ndarray, eligible: np.ndarray
) -> np.ndarray:
    """``marked`` grown across strips: a long straight crease on the boundary of a face beside a marked one, within
    :data:`STRIP_DEG` of parallel to it and no farther from its line than ``tan STRIP_DEG`` of their length (a
    strip, not a grid's square: 24 marked creases of a grid of squares became 5,001 without this), is marked too, and
    so on. Split on one side only, a strip between parallel
    creases fans from the whole side's ends to the split side's new vertices (24 pleats 8 mm apart: corners of
    0.45–0.89°), a needle the next round would split: one round, not one per strip (120 pleats, an arc beside the
    first: 64 triangulations before)."""
    if not marked.any():
        return marked
    v, e = pattern.vertices, pattern.edges
    direction = v[e[:, 1]] - v[e[:, 0]]
    length = np.hypot(*direction.T)
    direction = direction / np.maximum(length, 1e-300)[:, None]
    middle = 0.5 * (v[e[:, 0]] + v[e[:, 1]])
    cos_max, thin = math.cos(math.radians(STRIP_DEG)), math.tan(math.radians(STRIP_DEG))
    faces_of: dict[int, set[int]] = {}
    edges_of: list[list[int]] = []
    for f, loops in enumerate(pt.face_loops):
        on_face: list[int] = []
        for loop in loops:
            ring = loop.tolist()
            for a, b in zip(ring, ring[1:] + ring[:1], strict=True):
                edge = pt.segment_of.get((min(a, b), max(a, b)))
                if edge is not None and eligible[edge]:
                    on_face.append(edge)
                    faces_of.setdefault(edge, set()).add(f)
        edges_of.append(on_face)
    out = marked.copy()
    queue = np.flatnonzero(marked).tolist()
    while queue:
        k = queue.pop()
        for f in faces_of.get(k, ()):
            for other in edges_of[f]:
                if out[other] or abs(float(direction[k] @ direction[other])) < cos_max:
                    continue
                gap = middle[other] - v[e[k, 0]]
                width = abs(float(direction[k, 0] * gap[1] - direction[k, 1] * gap[0]))
                if width <= thin * max(float(length[k]), float(length[other])):  # a strip, not a grid's square
                    out[other] = True
                    queue.append(other)
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
    if not (interval > 0 and math.isfinite(interval)):  # an infinite interval keeps every crease whole
        return pattern, pt
    for _ in range(MAX_ROUNDS - 1):
        which = needle_creases(pattern, pt, interval)
        if not which.any():
            return pattern, pt
        yield "triangulated"
        step, note = _within_budget(pattern, which, interval)
        pattern = subdivide_edges(pattern, which, step)
        pt = constrained_triangulation(pattern, backend)
        if note:  # the segment budget is spent: no further round
            return replace(pattern, warnings=[*pattern.warnings, note]), pt
    if needle_creases(pattern, pt, interval).any():
        corner = float(corner_angles(pt.vertices, pt.triangles).min())
        note = (
            f"meshing: needles are left beside long straight creases after {MAX_ROUNDS - 1} round(s) of splits "
            f"(the mesh's smallest corner {corner:.2f}°)"
        )
        pattern = replace(pattern, warnings=[*pattern.warnings, note])
    return pattern, pt


def _lines(pattern: CreasePattern, which: np.ndarray) -> str:
    """The lines ``which`` selects, counted as a warning names them: "3 straight crease(s)", "2 straight cut(s)",
    or both: a cut is split beside needles as a crease is, and the warnings called every one a crease."""
    cuts = int(np.count_nonzero(np.asarray(pattern.assignments)[which] == "C"))
    creases = int(np.count_nonzero(which)) - cuts
    named = [f"{n} straight {kind}(s)" for n, kind in ((creases, "crease"), (cuts, "cut")) if n]
    return " and ".join(named)


def _within_budget(pattern: CreasePattern, which: np.ndarray, interval: float) -> tuple[float, str]:
    """The interval to split ``which`` at, and a warning (or ""): ``interval``, or larger where its pieces would take
    the pattern past the discretisation's :data:`~..pattern.discretize.MAX_SEGMENTS` (150 pleats 2 mm apart on a
    1 m sheet, a curve among them, at a 0.5 mm interval: 300,000 pieces), as the discretisation enlarges its own
    parameters; ``inf`` (no split) when not even one more piece fits."""
    e = pattern.edges[which]
    length = np.hypot(*(pattern.vertices[e[:, 1]] - pattern.vertices[e[:, 0]]).T)
    room = MAX_SEGMENTS - (pattern.n_edges - len(e))  # pieces the creases to split may become
    if float(np.ceil(length / interval).sum()) <= room:
        return interval, ""
    if room <= len(e):
        return math.inf, (
            f"meshing: {_lines(pattern, which)} beside needles were not split: the pattern already has "
            f"{pattern.n_edges} segments (limit {MAX_SEGMENTS})"
        )
    lo, hi = interval, float(length.max())  # too many pieces at lo, one piece each (≤ room) at hi
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if float(np.ceil(length / mid).sum()) > room else (lo, mid)
    return hi, (
        f"meshing: splitting {_lines(pattern, which)} beside needles at the interval {interval:g} mm would make "
        f"more than {MAX_SEGMENTS} segments; split at {hi:.4g} mm"
    )
