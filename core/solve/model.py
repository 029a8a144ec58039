"""Origami Simulator's bar-and-hinge model built from a :class:`~.mesh.FoldMesh` (reference §2–3).

The model is plain arrays in *normalised* units: the flat sheet is centred on its bounding-box centre and scaled by
``1 / R`` (``R`` = bounding-sphere radius around that centre), exactly as Origami Simulator does, so every stiffness
and tolerance below acts on a sheet that fits in a unit sphere whatever the pattern's units or size. Results are
mapped back to millimetres with :meth:`BarHingeModel.to_mm`.

Elements (reference §3.2):

* **axial bars** on every mesh edge: ``k = axial_stiffness / L0``, damping ``c = 2ζ√k`` (unit masses);
* **hinges** on every edge with exactly two triangles. M/V edges with a non-zero target are *creases*
  (``k = crease_stiffness · L0``, target = fold angle), F edges and M/V edges with angle 0 (or no angle, which
  Origami Simulator drives flat) are *facets* (``k = panel_stiffness · L0``, target 0). U and interior B edges get
  a hinge of stiffness 0: they are free, but their fold angle is still tracked and reported;
* **face-angle springs** on the three corners of every triangle (``k_f = face_stiffness``, no length scaling).

Glue (issue 17, :func:`with_glue`) appends **zero-length bars** between glued vertex pairs after the mesh's bars:
energy ``½ k ℓ²``, so they pull the pair together and their length at equilibrium is the remaining gap.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..mesh.fold_mesh import FoldMesh
from ..pattern.model import PatternError

FLAT_RATIO = float(np.tan(np.radians(2.0)))
"""A hinge's wing closer to the hinge line than this times the shortest side of its triangle lies in a *flat*
triangle (its largest corner above ~176°: the ear three consecutive nodes of a finely discretised curve make where
nothing else is near). There the stiffness fades out smoothly, to zero before the line (:data:`FLAT_DEAD`,
``forces.flat_attenuation``): the fold angle of a hinge is undefined when its wing crosses the hinge line, it jumps
by 180° as the triangle turns inside out, and so did the energy, which stalled the solver where two creases meet
tangentially or a curve crosses straight creases (tests/test_hinge_hessian.py, tests/test_robust_hard_cases.py).
2° is the mesh's own sliver bound (``mesh.ruling.SWAP_MIN_CORNER_DEG``)."""

FLAT_FRACTION = 0.5
"""A wing already that close to its hinge line at rest (an ear of a curve in the flat sheet) fades only once squashed
below this fraction of its rest moment arm: at rest, and as long as the paper keeps its shape, every hinge is
Origami Simulator's (fading them from the flat sheet on changed folds: a spiral's crease lost its drive along its
ears and no longer converged at 100 %)."""

FLAT_DEAD = 0.1
"""Below this fraction of its fading scale a wing's hinge has no stiffness at all: its triangle is pressed flat and has
no dihedral angle (its plane turns freely about the hinge line for a move of the wing of ~h). With a stiffness that
only fades, the last ~1e-6 of it turned that free plane in steps of ~0.25° per Newton iteration: three fuzz folds
(57–175 faces) crawled to the 500-iteration budget at residuals 1e-6 … 2e-4, the energy changing by 1e-9 per step.
The fading ``σ`` runs from 0 at this fraction to 1 at the scale (C² at both ends)."""


@dataclass
class BarHingeModel:
    """Arrays of one bar-and-hinge model (normalised units, unit node masses).

    ``hinge_wings`` holds ``(w1, w2)``, ``hinge_edge_nodes`` holds ``(v1, v2)`` in the mesh edge's order;
    ``w1`` is the apex of the triangle whose winding contains the directed edge ``v1 → v2`` (reference §3.4).
    ``hinge_target`` is the fold angle at 100 % in radians (valley > 0). ``hinge_is_crease`` marks driven creases
    (their target scales with the fold percent; facets stay at 0).
    """

    rest: np.ndarray
    center: np.ndarray
    scale: float
    triangles: np.ndarray
    bar_nodes: np.ndarray
    bar_length: np.ndarray
    bar_k: np.ndarray
    bar_c: np.ndarray
    hinge_edge: np.ndarray
    hinge_edge_nodes: np.ndarray
    hinge_wings: np.ndarray
    hinge_faces: np.ndarray
    hinge_k: np.ndarray
    hinge_target: np.ndarray
    hinge_is_crease: np.ndarray
    face_alpha0: np.ndarray
    face_k: float
    n_edges: int
    n_glue: int = 0
    hinge_flat_scale: np.ndarray | None = None
    """``(h, 2)``: per hinge and wing, the moment arm below which the hinge's stiffness fades out
    (:data:`FLAT_RATIO` times the shortest side of the wing's triangle at rest, or :data:`FLAT_FRACTION` of its
    rest moment arm if that is less; ``forces.flat_attenuation``)."""

    @property
    def n_nodes(self) -> int:
        return len(self.rest)

    def to_mm(self, x: np.ndarray) -> np.ndarray:
        """Normalised positions ``(n, 3)`` → millimetres in the input's frame (flat sheet back where it was)."""
        return np.asarray(x) / self.scale + self.center

    def from_mm(self, positions: np.ndarray) -> np.ndarray:
        """Millimetre positions ``(n, 3)`` → normalised model units."""
        return (np.asarray(positions, dtype=np.float64) - self.center) * self.scale

    def targets(self, percent: float) -> np.ndarray:
        """Per-hinge target angle (rad) at fold percent ``percent`` (1.0 = 100 %); facets stay at 0."""
        return self.hinge_target * float(percent)


def corner_angles(p: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Interior angles ``(t, 3)`` (rad) at corners a, b, c of every triangle for positions ``p`` (2D or 3D)."""
    a, b, c = (p[triangles[:, k]] for k in range(3))

    def unit(v: np.ndarray) -> np.ndarray:
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    ab, ac, bc = unit(b - a), unit(c - a), unit(c - b)
    dot = lambda u, v: np.clip(np.einsum("ij,ij->i", u, v), -1.0, 1.0)  # noqa: E731
    return np.stack([np.arccos(dot(ab, ac)), np.arccos(-dot(ab, bc)), np.arccos(dot(ac, bc))], axis=1)


def _hinge_topology(mesh: FoldMesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For every mesh edge, its two triangles ``(face1, face2)`` (``-1`` if absent) and wings ``(w1, w2)``.

    ``face1`` is the triangle whose winding contains ``edges[e, 0] → edges[e, 1]``. Raises :class:`PatternError`
    for an edge used by more than two triangles or twice in the same direction (inconsistent orientation).
    """
    tri = mesh.triangles
    n = max(mesh.n_vertices, 1)
    t_idx = np.repeat(np.arange(len(tri)), 3)
    src = tri.reshape(-1)
    dst = tri[:, [1, 2, 0]].reshape(-1)
    apex = tri[:, [2, 0, 1]].reshape(-1)
    lo, hi = np.minimum(src, dst), np.maximum(src, dst)
    edge_key = mesh.edges[:, 0] * n + mesh.edges[:, 1]
    order = np.argsort(edge_key)
    side_key = lo * n + hi
    pos = np.searchsorted(edge_key[order], side_key)
    pos = np.clip(pos, 0, max(len(order) - 1, 0))
    if len(order) == 0 or not np.all(edge_key[order][pos] == side_key):
        bad = int(np.flatnonzero(edge_key[order][pos] != side_key)[0]) if len(order) else 0
        raise PatternError(
            f"triangle {bad // 3} side ({src[bad]}, {dst[bad]}) is missing from the edge list (inconsistent mesh)"
        )
    side_edge = order[pos]
    forward = src == mesh.edges[side_edge, 0]
    e = len(mesh.edges)
    faces = np.full((e, 2), -1, dtype=np.int64)
    wings = np.full((e, 2), -1, dtype=np.int64)
    for col, mask in ((0, forward), (1, ~forward)):
        counts = np.bincount(side_edge[mask], minlength=e)
        if np.any(counts > 1):
            bad = int(np.flatnonzero(counts > 1)[0])
            raise PatternError(
                f"mesh edge {bad} ({mesh.edges[bad, 0]}, {mesh.edges[bad, 1]}) is shared by two triangles with the "
                "same orientation (non-manifold or inconsistently wound triangles)"
            )
        faces[side_edge[mask], col] = t_idx[mask]
        wings[side_edge[mask], col] = apex[mask]
    return faces, wings, side_edge


def build_model(
    mesh: FoldMesh,
    *,
    axial_stiffness: float = 20.0,
    crease_stiffness: float = 0.7,
    panel_stiffness: float = 0.7,
    face_stiffness: float = 0.2,
    damping: float = 0.45,
) -> BarHingeModel:
    """Build the normalised bar-and-hinge model of ``mesh`` with Origami Simulator's element rules (reference §3)."""
    if mesh.n_vertices < 3 or len(mesh.triangles) == 0:
        raise PatternError(
            f"the mesh has {mesh.n_vertices} vertices and {len(mesh.triangles)} triangles: nothing to fold"
        )
    if len(mesh.assignments) != len(mesh.edges) or len(mesh.fold_angles) != len(mesh.edges):
        raise PatternError(
            f"mesh arrays disagree: {len(mesh.edges)} edges, {len(mesh.assignments)} assignments, "
            f"{len(mesh.fold_angles)} fold angles"
        )
    flat = mesh.vertices_3d
    lo, hi = flat.min(axis=0), flat.max(axis=0)
    center = 0.5 * (lo + hi)
    radius = float(np.max(np.linalg.norm(flat - center, axis=1)))
    if not np.isfinite(radius) or radius <= 0:
        raise PatternError(
            f"the mesh has no extent (bounding-sphere radius {radius}); vertices must be finite and distinct"
        )
    scale = 1.0 / radius
    rest = (flat - center) * scale

    bars = mesh.edges.copy()
    length = np.linalg.norm(rest[bars[:, 1]] - rest[bars[:, 0]], axis=1)
    if np.any(length <= 0):
        bad = int(np.flatnonzero(length <= 0)[0])
        raise PatternError(f"mesh edge {bad} ({bars[bad, 0]}, {bars[bad, 1]}) has zero length (duplicate vertices)")
    bar_k = axial_stiffness / length
    bar_c = 2.0 * damping * np.sqrt(bar_k)

    faces, wings, _ = _hinge_topology(mesh)
    interior = np.all(faces >= 0, axis=1)
    hinge_edge = np.flatnonzero(interior)
    assign = mesh.assignments[hinge_edge]
    angle = mesh.fold_angles[hinge_edge]
    mv = np.isin(assign, ("M", "V"))
    crease = mv & np.isfinite(angle) & (angle != 0)
    facet = (assign == "F") | (mv & ~crease)
    k = np.where(crease, crease_stiffness, np.where(facet, panel_stiffness, 0.0)) * length[hinge_edge]
    target = np.where(crease, np.deg2rad(np.nan_to_num(angle)), 0.0)

    alpha0 = corner_angles(rest, mesh.triangles)
    if not np.all(np.isfinite(alpha0)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(alpha0), axis=1))[0])
        raise PatternError(f"triangle {bad} {mesh.triangles[bad].tolist()} is degenerate (zero-length side)")
    corners = rest[mesh.triangles]
    shortest = np.min(np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2), axis=1)
    edge = mesh.edges[hinge_edge]
    chord = rest[edge[:, 1]] - rest[edge[:, 0]]
    chord /= np.linalg.norm(chord, axis=1)[:, None]
    arms = []
    for w in range(2):  # each wing's moment arm at rest: its distance from the hinge line
        r = rest[wings[hinge_edge][:, w]] - rest[edge[:, 0]]
        arms.append(np.linalg.norm(r - np.sum(r * chord, axis=1)[:, None] * chord, axis=1))
    flat_scale = np.minimum(FLAT_RATIO * shortest[faces[hinge_edge]], FLAT_FRACTION * np.column_stack(arms))
    flat_scale = np.maximum(flat_scale, 1e-12)  # a wing on its hinge line already at rest: no division by zero
    return BarHingeModel(
        rest=rest,
        center=center,
        scale=scale,
        triangles=mesh.triangles.copy(),
        bar_nodes=bars,
        bar_length=length,
        bar_k=bar_k,
        bar_c=bar_c,
        hinge_edge=hinge_edge,
        hinge_edge_nodes=mesh.edges[hinge_edge].copy(),
        hinge_wings=wings[hinge_edge],
        hinge_faces=faces[hinge_edge],
        hinge_k=k,
        hinge_target=target,
        hinge_is_crease=crease,
        face_alpha0=alpha0,
        hinge_flat_scale=flat_scale,
        face_k=float(face_stiffness),
        n_edges=len(mesh.edges),
    )


def with_glue(model: BarHingeModel, pairs: np.ndarray, stiffness: float, damping: float = 0.45) -> BarHingeModel:
    """``model`` with a zero-length bar of stiffness ``stiffness`` (normalised units) between each vertex pair of
    ``pairs`` ``(g, 2)``, appended after its bars (the last ``n_glue`` bars are glue)."""
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    if len(pairs) == 0:
        return model
    k = np.full(len(pairs), float(stiffness))
    return replace(
        model,
        bar_nodes=np.concatenate([model.bar_nodes, pairs]),
        bar_length=np.concatenate([model.bar_length, np.zeros(len(pairs))]),
        bar_k=np.concatenate([model.bar_k, k]),
        bar_c=np.concatenate([model.bar_c, 2.0 * damping * np.sqrt(k)]),
        n_glue=model.n_glue + len(pairs),
    )


def mesh_from_triangles(
    vertices: np.ndarray,
    triangles: np.ndarray,
    creases: dict[tuple[int, int], tuple[str, float]] | None = None,
) -> FoldMesh:
    """A :class:`FoldMesh` from flat vertices and counter-clockwise triangles (hand-built meshes, tests, benchmarks).

    Every triangle side becomes an edge; sides on one triangle are borders ``B``, the others facets ``F`` (angle 0)
    unless ``creases`` maps the vertex pair (either order) to ``(assignment, fold angle in degrees)``.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    sides = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
    edges, counts = np.unique(sides, axis=0, return_counts=True)
    assignments = np.where(counts == 1, "B", "F").astype("<U1")
    angles = np.where(counts == 1, np.nan, 0.0)
    lookup = {(int(a), int(b)): k for k, (a, b) in enumerate(edges)}
    for (a, b), (assignment, angle) in (creases or {}).items():
        key = (min(a, b), max(a, b))
        if key not in lookup:
            raise PatternError(f"crease ({a}, {b}) is not a side of any triangle")
        assignments[lookup[key]] = assignment
        angles[lookup[key]] = angle
    return FoldMesh(
        vertices=vertices,
        triangles=triangles,
        edges=edges,
        assignments=assignments,
        fold_angles=angles,
        edge_from_curve=np.zeros(len(edges), bool),
        edge_polyline=np.full(len(edges), -1),
        triangle_face=np.zeros(len(triangles), np.int64),
        mesh_type="manual",
    )
