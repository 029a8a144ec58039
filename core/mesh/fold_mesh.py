"""The triangle mesh the solver folds (paper §3.2–3.3 output), as plain arrays.

A :class:`FoldMesh` is built from a :class:`~.pattern.CreasePattern` by ``core.mesh.triangulate`` (constrained
Delaunay, no interior points) and ``core.mesh.ruling`` (edge swaps along estimated rulings). It carries everything later
stages need: the flat positions, consistently oriented triangles, every triangle side as an edge with its
assignment and target fold angle, and the crease-pattern face each triangle came from (the warp angle walks
along that face's boundary).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass
class FoldMesh:
    """A triangulated crease pattern, flat, in millimetres.

    Arrays (``n`` vertices, ``t`` triangles, ``e`` edges):

    * ``vertices`` ``(n, 2)`` float64: flat positions in the sheet's plane (the folded state adds z)
    * ``triangles`` ``(t, 3)`` int64: counter-clockwise seen from +z, so every flat normal is +z
    * ``edges`` ``(e, 2)`` int64: every triangle side exactly once, ``edges[:, 0] < edges[:, 1]``
    * ``assignments`` ``(e,)`` ``B M V F U`` (cuts are split into two border edges, new diagonals are ``F``)
    * ``fold_angles`` ``(e,)`` float64 target fold angles in degrees (FOLD sign: valley > 0); ``F`` → 0,
      ``B``/``U`` → ``nan`` (no hinge target)
    * ``edge_from_curve`` ``(e,)`` bool: the edge discretises a drawn curve
    * ``edge_polyline`` ``(e,)`` int64: source polyline of a crease/border edge (index into the pattern's
      ``sources``), ``-1`` for diagonals added by triangulation
    * ``triangle_face`` ``(t,)`` int64: index into ``faces``
    * ``faces``: the crease-pattern faces as counter-clockwise vertex loops (arrays of vertex indices)

    ``mesh_type`` is ``"earcut"``, ``"cdt"`` or ``"ruling"``; ``swaps`` counts the edge swaps applied;
    ``generation_ms`` is the wall time of triangulation plus swaps; ``interval`` the pattern's discretisation
    interval (mm; nan if unknown), which a FOLD file of the mesh keeps so that, read back, it meshes the same.
    """

    vertices: np.ndarray
    triangles: np.ndarray
    edges: np.ndarray
    assignments: np.ndarray
    fold_angles: np.ndarray
    edge_from_curve: np.ndarray
    edge_polyline: np.ndarray
    triangle_face: np.ndarray
    faces: list[np.ndarray] = field(default_factory=list)
    mesh_type: str = "ruling"
    swaps: int = 0
    generation_ms: float = 0.0
    sources: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    interval: float = math.nan

    def __post_init__(self) -> None:
        self.vertices = np.asarray(self.vertices, dtype=np.float64).reshape(-1, 2)
        self.triangles = np.asarray(self.triangles, dtype=np.int64).reshape(-1, 3)
        self.edges = np.asarray(self.edges, dtype=np.int64).reshape(-1, 2)
        self.assignments = np.asarray(self.assignments, dtype="<U1").reshape(-1)
        self.fold_angles = np.asarray(self.fold_angles, dtype=np.float64).reshape(-1)
        self.edge_from_curve = np.asarray(self.edge_from_curve, dtype=bool).reshape(-1)
        self.edge_polyline = np.asarray(self.edge_polyline, dtype=np.int64).reshape(-1)
        self.triangle_face = np.asarray(self.triangle_face, dtype=np.int64).reshape(-1)

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def n_faces(self) -> int:
        """Number of triangles (the paper's #F)."""
        return len(self.triangles)

    @property
    def vertices_3d(self) -> np.ndarray:
        """Flat positions with z = 0, shape ``(n, 3)``."""
        return np.column_stack([self.vertices, np.zeros(len(self.vertices))])

    @property
    def diagonal(self) -> float:
        """Length of the flat bounding-box diagonal (mm): the scale errors are divided by."""
        return float(np.linalg.norm(self.vertices.max(axis=0) - self.vertices.min(axis=0)))

    def is_crease(self) -> np.ndarray:
        """Mask of driven creases: M or V edges with a finite non-zero target."""
        return np.isin(self.assignments, ("M", "V")) & np.isfinite(self.fold_angles) & (self.fold_angles != 0)

    def signed_areas(self) -> np.ndarray:
        """Twice the signed flat area of each triangle (> 0 for counter-clockwise)."""
        a, b, c = (self.vertices[self.triangles[:, k]] for k in range(3))
        return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])


def corner_angles(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Corner angles ``(t, 3)`` in degrees of triangles on 2D or 3D ``vertices``; column k is the corner at
    ``triangles[:, k]`` (``atan2(|u × w|, u · w)``: accurate near 0° and 180°)."""
    p = np.asarray(vertices, dtype=float)
    if p.shape[1] == 2:
        p = np.column_stack([p, np.zeros(len(p))])
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    out = np.empty((len(t), 3))
    for k in range(3):
        a, b, c = p[t[:, k]], p[t[:, (k + 1) % 3]], p[t[:, (k + 2) % 3]]
        u, w = b - a, c - a
        out[:, k] = np.degrees(np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), np.einsum("ij,ij->i", u, w)))
    return out


def segments_by_angle(vertices: np.ndarray, segments: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every segment once from each of its ends, sorted by that end and then by direction: ``(ends, angle, row)``,
    ``ends[:, 0]`` the vertex and ``ends[:, 1]`` the other end, ``angle`` the direction (radians, ``arctan2``) and
    ``row`` the row of ``segments`` it is; a vertex's segments are one run, counter-clockwise."""
    segments = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    ends = np.concatenate([segments, segments[:, ::-1]])
    row = np.tile(np.arange(len(segments)), 2)
    d = vertices[ends[:, 1]] - vertices[ends[:, 0]]
    angle = np.arctan2(d[:, 1], d[:, 0])
    order = np.lexsort((angle, ends[:, 0]))
    return ends[order], angle[order], row[order]


def polygon_sides(polygons: np.ndarray) -> np.ndarray:
    """The sides ``(k·m, 2)`` of ``k`` polygons given as rows of ``m`` vertex indices, each as a sorted vertex pair
    (row ``i·m + j`` is the side from corner ``j`` of polygon ``i`` to the next)."""
    rows = np.asarray(polygons, dtype=np.int64)
    return np.sort(np.stack([rows, np.roll(rows, -1, axis=1)], axis=-1).reshape(-1, 2), axis=1)
