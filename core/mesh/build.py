"""Crease pattern → :class:`~.mesh.FoldMesh`, with the mesh type selectable by name (paper §3.2–3.3 and baselines).

* ``"ruling"`` (default): constrained Delaunay triangulation, then the ruling-aware edge swaps (the paper's method)
  and the squash flips (:mod:`.squash`: no cap the fold can press flat);
* ``"cdt"``: the constrained Delaunay triangulation alone (the paper's "without swaps" column);
* ``"earcut"``: Origami Simulator's default: per crease-pattern face, triangles kept, quads split on the shorter
  diagonal, larger faces ear-clipped.

All three share the face finding of :func:`~.triangulate.constrained_triangulation` (regions between segments,
outside and holes removed) and the cut splitting.
"""

from __future__ import annotations

import contextlib
import gc
import time
from collections.abc import Generator, Iterator
from dataclasses import replace

import numpy as np

from .. import load_bpy, run_to_end
from ..pattern.model import CreasePattern
from ..pattern.polylines import connected_components
from .earcut import ear_clip
from .fold_mesh import FoldMesh
from .needles import split_needle_creases_steps
from .ruling import ruling_swaps_steps
from .triangulate import (
    _outer_first,
    constrained_triangulation,
    face_loops,
    orient,
    resolve_backend,
    split_cuts,
)

MESH_TYPES = ("ruling", "cdt", "earcut")


def _earcut_face(points: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Origami Simulator's per-face rule: keep triangles, split quads on the shorter (valid) diagonal, ear-clip."""
    n = len(loop)
    if n == 3:
        return loop[None, :].copy()
    if n == 4:
        a, b, c, d = (int(v) for v in loop)
        options = [
            ((a, b, c), (a, c, d), np.linalg.norm(points[a] - points[c])),
            ((b, c, d), (b, d, a), np.linalg.norm(points[b] - points[d])),
        ]
        options.sort(key=lambda o: o[2])
        for t1, t2, _ in options:
            if orient(*(points[list(t1)])) > 0 and orient(*(points[list(t2)])) > 0:
                return np.array([t1, t2], dtype=np.int64)
    return ear_clip(points, loop)


@contextlib.contextmanager
def _gc_paused() -> Iterator[None]:
    """Pause the cyclic garbage collector while building: generation allocates many small lists and tuples (no
    cycles), which otherwise trigger full collections over every object Blender has loaded (~20 % of the time)."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def build_mesh(pattern: CreasePattern, mesh_type: str = "ruling", backend: str = "auto") -> FoldMesh:
    """Triangulate a discretised crease pattern into a complete :class:`FoldMesh`.

    ``backend`` selects the CDT (``"auto"``, ``"triangle"``, ``"mathutils"``; same result). Every pattern segment
    becomes a mesh edge with its assignment and fold angle (cuts become two border edges); new diagonals are facets
    (``F``, target 0, ``edge_polyline`` −1). ``generation_ms`` is the wall time of triangulation and swaps.
    """
    return run_to_end(build_mesh_steps(pattern, mesh_type, backend))


def build_mesh_steps(
    pattern: CreasePattern, mesh_type: str = "ruling", backend: str = "auto"
) -> Generator[str, None, FoldMesh]:
    """:func:`build_mesh` in units of work (yields each unit's name, returns the mesh): the triangulation, the
    ruling swaps in units (:func:`.ruling.ruling_swaps_steps`) and the mesh's edges and faces. A Blender job runs
    one unit per slice; ``generation_ms`` counts the time spent in the units only."""
    if mesh_type not in MESH_TYPES:
        raise ValueError(f"unknown mesh type {mesh_type!r}; expected one of {MESH_TYPES}")
    _load_blender_modules(mesh_type, backend, pattern)  # in the first unit, not counted: it is not generation
    clock = _WorkClock()
    return (yield from clock.timed(_build_mesh_steps(pattern, mesh_type, backend, clock)))


class _WorkClock:
    """The time spent inside a generator's units, not in whoever runs them between units (Blender's UI)."""

    def __init__(self) -> None:
        self.spent = 0.0
        self._since: float | None = None

    def timed(self, steps: Generator[str, None, FoldMesh]) -> Generator[str, None, FoldMesh]:
        """Run ``steps`` unit by unit, each with the garbage collector paused (:func:`_gc_paused`), counting the
        time spent in them."""
        while True:
            self._since = time.perf_counter()
            try:
                with _gc_paused():
                    unit = next(steps)
            except StopIteration as done:
                return done.value
            self.spent += time.perf_counter() - self._since
            self._since = None
            yield unit

    def ms(self) -> float:
        """Milliseconds spent so far, the running unit included."""
        running = time.perf_counter() - self._since if self._since is not None else 0.0
        return (self.spent + running) * 1000.0


def _load_blender_modules(mesh_type: str, backend: str, pattern: CreasePattern) -> None:
    """Import what the chosen path needs from Blender (``bmesh`` for the swaps, ``mathutils`` for that CDT backend)
    before the clock starts: loading the ``bpy`` module once takes ~0.35 s CPU and is not mesh generation. A pattern
    without curve pieces makes no ruling swap, so the import waits until a squash flip needs ``bmesh``, if one does
    (CircularPleat-antiFacet never: its command-line fold to .fold no longer loads Blender, 3.3 → 3.0 s CPU)."""
    swaps = mesh_type == "ruling" and bool(np.any(pattern.edge_from_curve))
    if swaps or resolve_backend(backend) == "mathutils":
        load_bpy()  # bmesh and mathutils need bpy imported first in the bpy module


def _warn_separate_pieces(verts: np.ndarray, tris: np.ndarray, warnings: list[str]) -> None:
    """Warn when the sheet is in several pieces: a closed cut loop drawn for a hole leaves the cut-out disc in the
    mesh as a loose piece (the folded sheet passes through it and the self-intersection count grows), and two
    borders drawn side by side are two sheets. Each piece folds on its own; none is dropped."""
    label = connected_components(len(verts), tris[:, [0, 1, 2]].ravel(), tris[:, [1, 2, 0]].ravel())
    used = np.unique(tris)
    pieces, count = np.unique(label[used], return_counts=True)
    if len(pieces) < 2:
        return
    order = np.argsort(-count, kind="stable")
    smaller = [
        f"{count[k]} vertices around ({c[0]:.3f}, {c[1]:.3f}) mm"
        for k in order[1:4]
        for c in [verts[used[label[used] == pieces[k]]].mean(axis=0)]
    ]
    more = f" and {len(pieces) - 4} more" if len(pieces) > 4 else ""
    warnings.append(
        f"the sheet is in {len(pieces)} separate pieces (the largest has {count[order[0]]} vertices; the others: "
        f"{'; '.join(smaller)}{more}): each folds on its own — cuts (green) that close around a part cut it free; "
        "for a hole, draw its outline as a border (black): a closed cut leaves its disc as a loose piece"
    )


def _build_mesh_steps(
    pattern: CreasePattern, mesh_type: str, backend: str, clock: _WorkClock
) -> Generator[str, None, FoldMesh]:
    if mesh_type == "earcut":  # Origami Simulator's mesh: its straight creases stay whole
        pt = constrained_triangulation(pattern, backend)
    else:
        pattern, pt = yield from split_needle_creases_steps(pattern, backend)
    if len(pt.outline_edges):  # no border drawn: the outer boundary of the drawn segments is the border
        assignments = pattern.assignments.copy()
        assignments[pt.outline_edges] = "B"
        fold_angles = pattern.fold_angles.astype(float).copy()
        fold_angles[pt.outline_edges] = np.nan
        pattern = replace(pattern, assignments=assignments, fold_angles=fold_angles)
    warnings = list(pattern.warnings) + pt.warnings
    pts = pt.vertices
    tris, tface = pt.triangles, pt.triangle_region
    swaps = 0
    seg_pairs = np.array(sorted(pt.segment_of), dtype=np.int64).reshape(-1, 2)
    seg_index = np.array([pt.segment_of[tuple(p)] for p in seg_pairs.tolist()], dtype=np.int64)
    if mesh_type == "earcut":
        parts, faces_of = [], []
        for f, loop in enumerate(pt.faces):
            if pt.face_simple[f]:
                tri_f = _earcut_face(pts, loop)
            else:
                tri_f = tris[tface == f]
                warnings.append(
                    f"earcut: crease-pattern face {f} has a hole or a dangling crease; used its CDT triangles"
                )
            parts.append(tri_f)
            faces_of.append(np.full(len(tri_f), f, dtype=np.int64))
        tris, tface = np.concatenate(parts), np.concatenate(faces_of)
    elif mesh_type == "ruling":
        yield "triangulated"
        res = yield from ruling_swaps_steps(pts, tris, tface, seg_pairs, pattern.edge_from_curve[seg_index])
        tris, tface, swaps = res.triangles, res.triangle_face, res.swaps

    cut_pairs = {
        tuple(p) for p, k in zip(seg_pairs.tolist(), seg_index.tolist(), strict=True) if pattern.assignments[k] == "C"
    }
    verts, tris, origin = split_cuts(pts, tris, cut_pairs)
    generation_ms = clock.ms()
    _warn_separate_pieces(verts, tris, warnings)
    yield "cuts split"

    # edges: every triangle side once, i < j
    sides = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    edges = np.unique(np.sort(sides, axis=1), axis=0)
    o = np.sort(origin[edges], axis=1)
    n_pt = np.int64(len(pts))
    seg_code_pt = seg_pairs[:, 0] * n_pt + seg_pairs[:, 1]  # sorted: seg_pairs is in lexicographic order
    o_code = o[:, 0] * n_pt + o[:, 1]
    pos = np.clip(np.searchsorted(seg_code_pt, o_code), 0, max(len(seg_code_pt) - 1, 0))
    src = np.where(seg_code_pt[pos] == o_code, seg_index[pos], -1) if len(seg_code_pt) else np.full(len(o), -1)
    is_seg = src >= 0
    assignments = np.full(len(edges), "F", dtype="<U1")
    assignments[is_seg] = pattern.assignments[src[is_seg]]
    assignments[assignments == "C"] = "B"
    fold_angles = np.zeros(len(edges))
    fold_angles[is_seg] = pattern.fold_angles[src[is_seg]]
    fold_angles[np.isin(assignments, ("B", "U"))] = np.nan
    fold_angles[(assignments == "F") & ~np.isfinite(fold_angles)] = 0.0
    edge_from_curve = np.zeros(len(edges), dtype=bool)
    edge_from_curve[is_seg] = pattern.edge_from_curve[src[is_seg]]
    edge_polyline = np.full(len(edges), -1, dtype=np.int64)
    edge_polyline[is_seg] = pattern.edge_polyline[src[is_seg]]

    # crease-pattern face loops in the final (cut-split) numbering: the outer (largest) loop of each face
    n_v = np.int64(len(verts))
    seg_code = np.unique(edges[is_seg, 0] * n_v + edges[is_seg, 1])
    faces = [
        np.asarray(_outer_first(verts, loops)[0], dtype=np.int64)
        for loops in face_loops(verts, tris, tface, len(pt.faces), seg_code)
    ]

    mesh = FoldMesh(
        vertices=verts,
        triangles=tris,
        edges=edges,
        assignments=assignments,
        fold_angles=fold_angles,
        edge_from_curve=edge_from_curve,
        edge_polyline=edge_polyline,
        triangle_face=tface,
        faces=faces,
        mesh_type=mesh_type,
        swaps=swaps,
        generation_ms=generation_ms,
        sources=list(pattern.sources),
        warnings=warnings,
        interval=pattern.interval,
    )
    bad = np.flatnonzero(mesh.signed_areas() <= 0)
    if len(bad):  # pragma: no cover - every stage keeps triangles CCW; fail loudly if one does not
        raise RuntimeError(f"build_mesh({mesh_type}): triangle {int(bad[0])} is not counter-clockwise")
    return mesh
