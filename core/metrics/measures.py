"""Developability and accuracy metrics of a folded mesh (ground-truth.md §4), vectorised over edges and vertices.

Positions are ``(n, 3)`` millimetres in the mesh's vertex order. Conventions match Origami Simulator:

* fold angle (§3.4 of the model notes): for edge (v1, v2), face 1 is the triangle whose CCW winding contains
  v1→v2; θ = atan2((n1 × ê)·n2, n1·n2), valley > 0 (the sheet folds toward the +z side of its flat normals);
* warp angle (paper Fig. 6, authors' code, ground-truth §4.1): for non-crease edges folded by at least 0.5°, the
  angle between the planes span(r, t0) and span(r, t1), with t_k the central difference between v_k's two
  neighbours along the crease-pattern face boundary, in current positions; reported as the mean;
* strain (§4.2): per node, mean of |ℓ/L0 − 1| over incident edges; mean and max in %;
* angle defect (§4.3): 2π − Σ corner angles at interior vertices (0 for any isometric fold).
"""

from __future__ import annotations

import numpy as np

from ..mesh.fold_mesh import FoldMesh
from .mesh_quality import corner_summary

WARP_MIN_FOLD_DEG = 0.5
"""Edges folded less than this are "flat" and left out of the warp-angle mean (authors' threshold)."""


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / n


def edge_triangles(mesh: FoldMesh) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(face1, face2, wing1, wing2)`` per edge: the triangle containing v1→v2 (resp. v2→v1) in its CCW winding
    and its vertex opposite the edge; −1 where the edge is on the boundary."""
    t = mesh.triangles
    e = len(mesh.edges)
    n = max(mesh.n_vertices, 1)
    src = t.reshape(-1)
    dst = np.roll(t, -1, axis=1).reshape(-1)
    opp = np.roll(t, -2, axis=1).reshape(-1)
    tri = np.repeat(np.arange(len(t)), 3)
    he_key = src * n + dst
    order = np.argsort(he_key)
    sorted_keys = he_key[order]
    out = []
    for a, b in ((mesh.edges[:, 0], mesh.edges[:, 1]), (mesh.edges[:, 1], mesh.edges[:, 0])):
        k = a * n + b
        pos = np.clip(np.searchsorted(sorted_keys, k), 0, len(sorted_keys) - 1)
        found = sorted_keys[pos] == k if len(sorted_keys) else np.zeros(e, dtype=bool)
        h = order[pos]
        out.append((np.where(found, tri[h], -1), np.where(found, opp[h], -1)))
    (f1, w1), (f2, w2) = out
    return f1, f2, w1, w2


def triangle_normals(mesh: FoldMesh, positions: np.ndarray) -> np.ndarray:
    """Unit normals ``(t, 3)`` of the triangles at ``positions`` (flat: +z)."""
    p = np.asarray(positions, dtype=float)
    a, b, c = (p[mesh.triangles[:, k]] for k in range(3))
    return _unit(np.cross(b - a, c - a))


def fold_angles(mesh: FoldMesh, positions: np.ndarray) -> np.ndarray:
    """Signed fold angle per edge in degrees (valley > 0), ``nan`` on boundary edges."""
    p = np.asarray(positions, dtype=float)
    f1, f2, _, _ = edge_triangles(mesh)
    nrm = triangle_normals(mesh, p)
    inner = (f1 >= 0) & (f2 >= 0)
    out = np.full(len(mesh.edges), np.nan)
    n1, n2 = nrm[f1[inner]], nrm[f2[inner]]
    e = _unit(p[mesh.edges[inner, 1]] - p[mesh.edges[inner, 0]])
    out[inner] = np.degrees(np.arctan2(np.einsum("ij,ij->i", np.cross(n1, e), n2), np.einsum("ij,ij->i", n1, n2)))
    return out


def unwrapped_fold_angles(
    mesh: FoldMesh, frames: list[np.ndarray], start: np.ndarray | None = None
) -> list[np.ndarray]:
    """:func:`fold_angles` of each of ``frames`` (positions, mm, in the order they fold), each angle taken by whole
    turns to the one nearest the last frame's (the first frame's nearest ``start``, default flat: 0).

    The geometry gives angles in (−180°, 180°], so a valley driven past flat (199°) reads −161°, the wrong sign for
    its assignment; the solver keeps them unwrapped, and this follows the frames as it does. (An export of the
    add-on's frames wrote such valleys as −161° to −168° where the command line writes the solver's 180°.)"""
    follow = AngleFollower(mesh, start)
    return [follow(positions) for positions in frames]


class AngleFollower:
    """:func:`unwrapped_fold_angles` one frame at a time: each call takes the next frame's positions (mm) and returns
    its unwrapped angles, so an export job can measure a frame per unit of work (60 frames of a 3,000-face pattern
    took 63 ms in one call)."""

    def __init__(self, mesh: FoldMesh, start: np.ndarray | None = None):
        self.mesh = mesh
        self.last = np.zeros(len(mesh.edges)) if start is None else np.nan_to_num(np.asarray(start, dtype=float))

    def __call__(self, positions: np.ndarray) -> np.ndarray:
        a = fold_angles(self.mesh, positions)
        a = a + 360.0 * np.round((self.last - a) / 360.0)
        self.last = np.where(np.isfinite(a), a, self.last)
        return a


def edge_strain(mesh: FoldMesh, positions: np.ndarray) -> np.ndarray:
    """|ℓ/L0 − 1| per edge."""
    p = np.asarray(positions, dtype=float)
    flat = mesh.vertices_3d
    e = mesh.edges
    length0 = np.linalg.norm(flat[e[:, 1]] - flat[e[:, 0]], axis=1)
    length = np.linalg.norm(p[e[:, 1]] - p[e[:, 0]], axis=1)
    return np.abs(length / length0 - 1.0)


def strain(mesh: FoldMesh, positions: np.ndarray) -> np.ndarray:
    """Origami Simulator's per-node strain: mean of |ℓ/L0 − 1| over the node's edges (a fraction, not %)."""
    s = edge_strain(mesh, positions)
    n = mesh.n_vertices
    total = np.bincount(mesh.edges.reshape(-1), weights=np.repeat(s, 2), minlength=n)
    degree = np.bincount(mesh.edges.reshape(-1), minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        return total / degree


def boundary_neighbours(mesh: FoldMesh) -> tuple[np.ndarray, np.ndarray]:
    """For each edge end ``(e, 2)``: the crease-pattern face-boundary neighbours (prev, next) of that vertex in
    the wedge around the edge, i.e. what walking around the vertex inside the face meets first on either side.

    Pattern segments (every edge with ``edge_polyline ≥ 0``) bound the faces; the wedge is found by angle among a
    vertex's segments in the flat state, which is the same as the walk (creases are never crossed). For an edge that
    is itself a segment, the segments on either side of it are used. ``-1`` where a vertex has no other segment.
    """
    v = mesh.vertices
    n = mesh.n_vertices
    seg = mesh.edges[mesh.edge_polyline >= 0]
    ends = np.concatenate([seg, seg[:, ::-1]])
    d = v[ends[:, 1]] - v[ends[:, 0]]
    ang = np.arctan2(d[:, 1], d[:, 0]) + np.pi  # [0, 2π]
    key = ends[:, 0] * 8.0 + ang
    order = np.argsort(key)
    key, other = key[order], ends[order, 1]
    start = np.searchsorted(key, np.arange(n) * 8.0)
    stop = np.searchsorted(key, np.arange(n) * 8.0 + 7.9)
    prev = np.full((len(mesh.edges), 2), -1, dtype=np.int64)
    nxt = np.full((len(mesh.edges), 2), -1, dtype=np.int64)
    for k, (p, q) in enumerate(((0, 1), (1, 0))):
        a = mesh.edges[:, p]
        dq = v[mesh.edges[:, q]] - v[a]
        qk = a * 8.0 + np.arctan2(dq[:, 1], dq[:, 0]) + np.pi
        lo, hi = start[a], stop[a]
        cnt = hi - lo
        ok = cnt > 0
        i_next = np.searchsorted(key, qk, side="right")
        i_prev = np.searchsorted(key, qk, side="left") - 1
        i_next = np.where(i_next >= hi, lo, i_next)  # wrap around within the vertex's block
        i_prev = np.where(i_prev < lo, hi - 1, i_prev)
        good = ok
        nxt[good, k] = other[i_next[good]]
        prev[good, k] = other[i_prev[good]]
    return prev, nxt


def warp_angles(mesh: FoldMesh, positions: np.ndarray, fold: np.ndarray | None = None) -> np.ndarray:
    """Warp angle per edge in degrees (ground-truth §4.1); ``nan`` for edges not counted (creases M/V, boundary,
    folded less than :data:`WARP_MIN_FOLD_DEG`, without face-boundary neighbours, or at a slit's tip, where the two
    neighbours are one flat point)."""
    p = np.asarray(positions, dtype=float)
    theta = fold_angles(mesh, p) if fold is None else fold
    counted = ~np.isin(mesh.assignments, ("M", "V")) & np.isfinite(theta) & (np.abs(theta) >= WARP_MIN_FOLD_DEG)
    prev, nxt = boundary_neighbours(mesh)
    counted &= np.all(prev >= 0, axis=1) & np.all(nxt >= 0, axis=1)
    out = np.full(len(mesh.edges), np.nan)
    idx = np.flatnonzero(counted)
    # at a slit's tip the two neighbours are the two lips' copies of one flat point: no tangent, and the plane the
    # gap between them spans is arbitrary (one 20 mm slit took a sheet's mean warp from 1.5° to 6.8°, max 89°)
    v = mesh.vertices
    span = np.hypot(*(v[mesh.edges[idx, 1]] - v[mesh.edges[idx, 0]]).T)
    idx = idx[np.all(np.hypot(*(v[nxt[idx]] - v[prev[idx]]).transpose(2, 0, 1)) > 1e-9 * span[:, None], axis=1)]
    if len(idx) == 0:
        return out
    e = mesh.edges[idx]
    r = p[e[:, 1]] - p[e[:, 0]]
    t0 = p[nxt[idx, 0]] - p[prev[idx, 0]]
    t1 = p[nxt[idx, 1]] - p[prev[idx, 1]]
    n0 = _unit(np.cross(t0, r))
    n1 = _unit(np.cross(t1, r))
    s = np.linalg.norm(np.cross(n0, n1), axis=1)
    out[idx] = np.degrees(np.arcsin(np.clip(s, 0.0, 1.0)))
    return out


def warp_per_triangle(mesh: FoldMesh, positions: np.ndarray, warp: np.ndarray | None = None) -> np.ndarray:
    """Warp angle per triangle (degrees) for display: the mean over its counted sides (:func:`warp_angles`), 0 where
    none of its sides is counted."""
    w = warp_angles(mesh, positions) if warp is None else np.asarray(warp, dtype=float)
    f1, f2, _, _ = edge_triangles(mesh)
    faces = np.concatenate([f1, f2])
    vals = np.concatenate([w, w])
    ok = (faces >= 0) & np.isfinite(vals)
    total = np.bincount(faces[ok], weights=vals[ok], minlength=mesh.n_faces)
    count = np.bincount(faces[ok], minlength=mesh.n_faces)
    return total / np.maximum(count, 1)


def interior_vertices(mesh: FoldMesh) -> np.ndarray:
    """Mask of vertices not on the mesh boundary."""
    f1, f2, _, _ = edge_triangles(mesh)
    on_boundary = np.zeros(mesh.n_vertices, dtype=bool)
    on_boundary[mesh.edges[(f1 < 0) | (f2 < 0)].reshape(-1)] = True
    return ~on_boundary


def angle_defect(mesh: FoldMesh, positions: np.ndarray) -> np.ndarray:
    """2π − Σ corner angles per vertex, in degrees; ``nan`` at boundary vertices."""
    p = np.asarray(positions, dtype=float)
    t = mesh.triangles
    total = np.zeros(mesh.n_vertices)
    for k in range(3):
        a, b, c = p[t[:, k]], p[t[:, (k + 1) % 3]], p[t[:, (k + 2) % 3]]
        u, w = b - a, c - a
        ang = np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), np.einsum("ij,ij->i", u, w))
        total += np.bincount(t[:, k], weights=ang, minlength=mesh.n_vertices)
    out = np.degrees(2.0 * np.pi - total)
    out[~interior_vertices(mesh)] = np.nan
    return out


def fold_angle_error(
    mesh: FoldMesh, positions: np.ndarray, percent: float = 1.0, fold: np.ndarray | None = None
) -> np.ndarray:
    """Simulated − target·percent fold angle per driven crease edge (degrees, in [−180, 180)), ``nan`` elsewhere.

    Angles measured from positions wrap at ±180°: a crease at 179.3° with a −180° target is 0.7° off, not 359.3°."""
    theta = fold_angles(mesh, positions) if fold is None else fold
    out = np.full(len(mesh.edges), np.nan)
    c = mesh.is_crease()
    out[c] = np.mod(theta[c] - mesh.fold_angles[c] * percent + 180.0, 360.0) - 180.0
    return out


def _nanmean(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    return float(x.mean()) if len(x) else float("nan")


def _nanmax(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    return float(x.max()) if len(x) else float("nan")


def summary(mesh: FoldMesh, positions: np.ndarray, percent: float = 1.0) -> dict[str, float]:
    """All the metrics at once: strain (mean/max %), warp (mean/max deg, edges counted), angle defect (mean/max
    |δ| deg), fold-angle error (mean/max |error| deg over driven creases), the mesh size, and the flat mesh's
    smallest corner and count of corners under 1° (:func:`.mesh_quality.corner_summary`)."""
    p = np.asarray(positions, dtype=float)
    theta = fold_angles(mesh, p)
    st = strain(mesh, p)
    warp = warp_angles(mesh, p, theta)
    defect = np.abs(angle_defect(mesh, p))
    err = np.abs(fold_angle_error(mesh, p, percent, theta)[mesh.is_crease()])
    return {
        "faces": float(mesh.n_faces),
        "strain_mean_pct": 100.0 * _nanmean(st),
        "strain_max_pct": 100.0 * _nanmax(st),
        "warp_mean_deg": _nanmean(warp),
        "warp_max_deg": _nanmax(warp),
        "warp_edges": float(np.count_nonzero(np.isfinite(warp))),
        "angle_defect_mean_deg": _nanmean(defect),
        "angle_defect_max_deg": _nanmax(defect),
        "fold_angle_error_mean_deg": _nanmean(err),
        "fold_angle_error_max_deg": _nanmax(err),
        **corner_summary(mesh),
    }
