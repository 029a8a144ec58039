"""A folded shape carried onto a re-meshed pattern: the warm start of a live re-fold after a curve was edited.

A live re-fold (scene/live.py) starts from the shape on screen, so a small edit (a handle dragged, one crease moved)
costs a few Newton iterations instead of a whole fold. When the edit changes the mesh, each new vertex starts at the
folded position of the point of the old sheet with its flat coordinates (:func:`transfer_positions`). That start
is only as good as the creases are where they were: when the whole drawing moves (the curves rotated 20° about Z,
scaled 1.05, a parent Empty scaled), every new crease lies on paper the old fold left flat, and a warm solve from
there converged in the cap to a mangled sheet (strain 0.81 % mean / 16.9 % max against the Re-fold's 0.25 / 1.06 %,
16.5 mm apart) or stalled. :func:`carried_shape` gives the start only when most of the new creases lie on old ones
(:func:`creases_in_place`); otherwise the re-fold folds from the flat sheet, as Re-fold does.
"""

from __future__ import annotations

from collections.abc import Generator

import numpy as np

from .. import run_to_end
from ..pattern.polylines import point_segment_distance
from .fold_mesh import FoldMesh

UNIT_PAIRS = 250_000
"""Point–triangle or point–segment pairs measured per unit of :func:`carried_shape_steps` (~10 ms): a live re-fold
runs them one unit per slice. In one call the carried shape of a 3,000-face pleat took 194–265 ms, the longest
slice of its live re-fold (a designer session)."""

IN_PLACE_SHARE = 0.9
"""A carried shape is a warm start when at least this share of the new creases' length lies on old creases of the
same role and fold angle. At 0.5 a reviewer's five-ring pleat with its two inner rings scaled 1.1 (76 % in place)
live-folded warm into a shape 55 mm RMS from Re-fold's: a pleat has many equilibria, and a start far from the
natural path's picks another one; so does every ring's angle changed (150° → 175°: 47 mm, unconverged in the
cap). An edit of one curve among many (a handle dragged, a point moved) keeps the warm start."""

IN_PLACE_DISTANCE = 1e-3
"""How near an old crease (a fraction of the sheet's diagonal: 0.25 mm on a 200 × 150 mm sheet) both ends of a new
crease edge must lie to count as in place. A curve sampled again after an edit elsewhere has its new vertices on the
same curve, within the discretisation's tolerance of the old chords."""


def transfer_positions(old: FoldMesh, old_positions: np.ndarray, new: FoldMesh) -> np.ndarray | None:
    """Each new vertex at the folded position of the point with its flat coordinates on the old mesh (barycentric
    in the old triangle containing it, or the nearest old vertex). Returns None when the sheets do not overlap
    (nothing to carry over)."""
    return run_to_end(transfer_positions_steps(old, old_positions, new))


def _rows(n_against: int) -> int:
    """Points per unit: :data:`UNIT_PAIRS` pairs with ``n_against`` triangles or segments each."""
    return max(1, UNIT_PAIRS // max(n_against, 1))


def transfer_positions_steps(
    old: FoldMesh, old_positions: np.ndarray | None, new: FoldMesh
) -> Generator[None, None, np.ndarray | None]:
    """:func:`transfer_positions` in units of :data:`UNIT_PAIRS` point–triangle pairs."""
    if old_positions is None:
        return None
    tri = old.triangles
    a, b, c = (old.vertices[tri[:, k], :2] for k in range(3))
    p = new.vertices[:, :2]
    out = np.empty((len(p), 3))
    found = np.zeros(len(p), dtype=bool)
    v0, v1 = b - a, c - a
    den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
    ok = np.abs(den) > 1e-15
    rows = _rows(len(tri))
    for lo in range(0, len(p), rows):
        if lo:
            yield
        q = p[lo : lo + rows, None, :] - a[None]
        u = (q[..., 0] * v1[None, :, 1] - v1[None, :, 0] * q[..., 1]) / np.where(ok, den, 1.0)
        v = (v0[None, :, 0] * q[..., 1] - q[..., 0] * v0[None, :, 1]) / np.where(ok, den, 1.0)
        inside = (u >= -1e-9) & (v >= -1e-9) & (u + v <= 1 + 1e-9) & ok[None]
        has = inside.any(axis=1)
        t = np.argmax(inside, axis=1)
        at = np.arange(len(t))
        uu, vv = u[at, t], v[at, t]
        pa, pb, pc = (old_positions[tri[t, k]] for k in range(3))
        out[lo : lo + rows] = pa + uu[:, None] * (pb - pa) + vv[:, None] * (pc - pa)
        found[lo : lo + rows] = has
    if not found.any():
        return None
    for i in np.flatnonzero(~found):
        out[i] = old_positions[np.argmin(np.sum((old.vertices[:, :2] - p[i]) ** 2, axis=1))]
    return out


def _creases(mesh: FoldMesh) -> np.ndarray:
    """The indices of the mountain and valley edges of ``mesh``."""
    return np.flatnonzero(np.isin(mesh.assignments, ("M", "V")))


def creases_in_place(old: FoldMesh, new: FoldMesh) -> float:
    """The share (by length) of ``new``'s mountain and valley edges whose two ends lie within
    :data:`IN_PLACE_DISTANCE` of the diagonal of a mountain or valley edge of ``old``, the one nearest its middle of
    the same role and target fold angle (1.0 when ``new`` has none)."""
    return run_to_end(creases_in_place_steps(old, new))


def creases_in_place_steps(old: FoldMesh, new: FoldMesh) -> Generator[None, None, float]:
    """:func:`creases_in_place` in units of :data:`UNIT_PAIRS` point–segment pairs."""
    new_index, old_index = _creases(new), _creases(old)
    new_edges, old_edges = new.edges[new_index], old.edges[old_index]
    if not len(new_edges):
        return 1.0
    p, q = new.vertices[new_edges[:, 0], :2], new.vertices[new_edges[:, 1], :2]
    length = np.hypot(*(q - p).T)
    if not len(old_edges) or length.sum() <= 0:
        return 0.0
    lo, hi = new.vertices.min(axis=0), new.vertices.max(axis=0)
    near = IN_PLACE_DISTANCE * float(np.hypot(*(hi - lo)))
    a, b = old.vertices[old_edges[:, 0], :2], old.vertices[old_edges[:, 1], :2]

    def nearest_old(points: np.ndarray) -> Generator[None, None, tuple[np.ndarray, np.ndarray]]:
        """Distance of each point from the old creases, and the nearest one."""
        dist, which = np.empty(len(points)), np.empty(len(points), dtype=np.int64)
        rows = _rows(len(a))
        for start in range(0, len(points), rows):
            yield
            chunk = points[start : start + rows]
            pairs = np.repeat(chunk, len(a), axis=0)
            d = point_segment_distance(pairs, np.tile(a, (len(chunk), 1)), np.tile(b, (len(chunk), 1)))
            d = d.reshape(len(chunk), len(a))
            which[start : start + rows] = np.argmin(d, axis=1)
            dist[start : start + rows] = d[np.arange(len(chunk)), which[start : start + rows]]
        return dist, which

    dp, _ = yield from nearest_old(p)
    dq, _ = yield from nearest_old(q)
    _, partner = yield from nearest_old(0.5 * (p + q))
    same = (new.assignments[new_index] == old.assignments[old_index[partner]]) & np.isclose(
        new.fold_angles[new_index], old.fold_angles[old_index[partner]], rtol=0.0, atol=1e-6, equal_nan=True
    )
    placed = (dp <= near) & (dq <= near) & same
    return float(length[placed].sum() / length.sum())


def carried_shape(old: FoldMesh, old_positions: np.ndarray | None, new: FoldMesh) -> np.ndarray | None:
    """The warm start of a re-meshed pattern: :func:`transfer_positions` when the creases are still where the old
    fold put them (:func:`creases_in_place` ≥ :data:`IN_PLACE_SHARE`), else None (fold from the flat sheet)."""
    return run_to_end(carried_shape_steps(old, old_positions, new))


def carried_shape_steps(
    old: FoldMesh, old_positions: np.ndarray | None, new: FoldMesh
) -> Generator[None, None, np.ndarray | None]:
    """:func:`carried_shape` in units (a Blender job runs one per slice)."""
    if old_positions is None:
        return None
    if (yield from creases_in_place_steps(old, new)) < IN_PLACE_SHARE:
        return None
    return (yield from transfer_positions_steps(old, old_positions, new))
