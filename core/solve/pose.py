"""Where a folded sheet sits in space: its centre face stays on the table.

The bar-and-hinge energy does not change when the whole sheet moves rigidly, so a solve leaves the sheet wherever
its damped steps happened to carry it. That placement depends on the path: the static fold at 100 % (four
continuation steps) and the last frame of a 30-frame animation had the same shape to 1e-8 but sat 0.75–2.4 mm apart
(0.7–2.4 % of the sheet), so a baked animation jumped away from the Fold it ends on, and a glTF animation did not
line up with an OBJ or FOLD export of the static fold.

Origami software fixes one face (ORIPA's and Rabbit Ear's "fixed face"); so do we. The reference face is the mesh
triangle nearest the sheet's centre among the well-shaped ones (smallest corner at least :data:`SHAPE_DEG`, or the
best-shaped ones if there are none; of several as near, the first by index); every fast solve's result is moved
rigidly so that this triangle lies where it was drawn, as well as its strain allows (a least-squares fit of its
three corners). The placement is then a function of the shape alone: the same for a static fold, an animation frame
and a live re-fold, on every front door. A single triangle is always well conditioned, where a best fit of the whole
folded sheet to the flat one is not (a sheet folded in half has no preferred turn about its crease). Pins decide the
pose themselves; where one pin, or two in a line, leave a turn free, the face chooses it (:func:`on_table`). A sheet
in several pieces (a hole drawn as a closed cut leaves a loose disc) places each piece on its own centre face,
unless glue joins them (then the whole sheet moves as one).
"""

from __future__ import annotations

import math

import numpy as np

from ..mesh.fold_mesh import FoldMesh, corner_angles
from ..pattern.polylines import connected_components
from .constraints import rigid_fit

SHAPE_DEG = 30.0
"""Triangles whose smallest corner is at least this (degrees) may hold the sheet; slivers would tilt with strain."""

NEAR_FRACTION = 1e-3
"""Triangles this close (÷ the sheet's size) to the nearest one are as near the centre: the first by index holds it."""


def reference_triangle(mesh: FoldMesh) -> np.ndarray:
    """The three vertex indices of the face that holds the whole sheet (see the module docstring)."""
    return _centre_triangles(mesh, np.zeros(len(mesh.triangles), dtype=np.int64))[0]


def resting_pieces(mesh: FoldMesh, together: bool = False) -> list[tuple[np.ndarray | None, np.ndarray]]:
    """Per piece of the sheet (its triangles joined by edges; a cut can leave a loose disc), the vertices it moves
    (``None``: all, when there is one piece) and the triangle that holds it on the table. ``together``: one
    placement for all (pieces glued to each other move as one)."""
    tri = np.asarray(mesh.triangles, dtype=np.int64)
    if together:
        return [(None, reference_triangle(mesh))]
    label = connected_components(mesh.n_vertices, tri[:, [0, 1, 2]].ravel(), tri[:, [1, 2, 0]].ravel())
    pieces, group = np.unique(label[tri[:, 0]], return_inverse=True)
    held = _centre_triangles(mesh, group.reshape(-1))
    if len(pieces) == 1:
        return [(None, held[0])]
    return [(np.flatnonzero(label == lab), held[k]) for k, lab in enumerate(pieces.tolist())]


def _centre_triangles(mesh: FoldMesh, group: np.ndarray) -> list[np.ndarray]:
    """For each group of triangles (``group[t]`` = 0, 1, …), its well-shaped triangle nearest its area centroid."""
    tri = np.asarray(mesh.triangles, dtype=np.int64)
    p = np.asarray(mesh.vertices_3d, dtype=np.float64)[tri]  # (t, 3 corners, 3)
    smallest = corner_angles(mesh.vertices, tri).min(axis=1)
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    middle = p.mean(axis=1)
    size = float(np.ptp(p.reshape(-1, 3), axis=0).max())
    out = []
    for g in range(int(group.max()) + 1 if len(group) else 0):
        mine = group == g
        centre = (middle[mine] * area[mine, None]).sum(axis=0) / max(float(area[mine].sum()), 1e-300)
        good = mine & (smallest >= min(SHAPE_DEG, float(smallest[mine].max())))
        distance = np.where(good, np.linalg.norm(middle - centre, axis=1), np.inf)
        # a symmetric pattern has several triangles at the same distance: the first of them by index, so that
        # float32 copies of the sheet (a Blender mesh) choose the same one as the float64 pattern
        near = distance <= distance.min() + NEAR_FRACTION * size
        out.append(tri[int(np.flatnonzero(near)[0])])
    return out


def on_table(
    positions: np.ndarray,
    flat: np.ndarray,
    pieces: list[tuple[np.ndarray | None, np.ndarray]],
    pins: np.ndarray | None = None,
) -> np.ndarray:
    """``positions`` ``(n, 3)`` mm with each piece (:func:`resting_pieces`) moved rigidly so that its triangle's
    corners come closest to where they are in ``flat`` (least squares; exactly there when unstrained). With
    ``pins`` (vertex indices; the result of a solve holds them where they are) a piece keeps its pins and only what
    they leave free is chosen by its face: a piece held by one pin is turned about it, by two (or more in a line)
    about their line, so that its face comes closest to where it was drawn; one held by three pins or more not in a
    line is left as it is. (A damped solve leaves the free turn where its path took it: a sheet on one or two pins
    crept about them at every warm re-fold, 1.07 mm more per 100 → 40 → 100 % cycle on one pin, 8.1 mm on two.)"""
    p = np.array(positions, dtype=np.float64)
    flat = np.asarray(flat, dtype=np.float64)
    pins = np.zeros(0, dtype=np.int64) if pins is None else np.asarray(pins, dtype=np.int64)
    for vertices, triangle in pieces:
        members = slice(None) if vertices is None else vertices
        at = pins if vertices is None else np.intersect1d(pins, vertices)  # the piece's pins
        held = np.unique(p[at], axis=0)
        if len(held) == 0:
            rot, shift = rigid_fit(p[triangle], flat[triangle])
            p[members] = p[members] @ rot + shift
            continue
        centre = held[0]
        spread = np.linalg.svd(held - centre, compute_uv=False) if len(held) > 1 else np.zeros(1)
        size = max(float(np.ptp(p[members], axis=0).max()), 1e-300)
        if len(spread) > 1 and spread[1] > 1e-9 * size:
            continue  # three pins or more, not in a line: the pose is theirs
        a, b = p[triangle] - centre, flat[triangle] - centre
        if spread[0] <= 1e-9 * size:  # one pin: the turn about it that fits the face best
            u, _, vt = np.linalg.svd(a.T @ b)
            rot = u @ np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt)) or 1.0]) @ vt
        else:  # pins in a line: the turn about it
            k = np.linalg.svd(held - centre)[2][0]
            a_perp, b_perp = a - np.outer(a @ k, k), b - np.outer(b @ k, k)
            phi = math.atan2(float(np.sum(np.cross(a_perp, b_perp) @ k)), float(np.sum(a_perp * b_perp)))
            cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
            turn = np.eye(3) + math.sin(phi) * cross + (1.0 - math.cos(phi)) * cross @ cross  # Rodrigues, columns
            rot = turn.T  # rows: v @ rot = turn v
        kept = p[at]
        p[members] = (p[members] - centre) @ rot + centre
        p[at] = kept  # on the axis of the turn: where they were, not moved by its round-off
    return p
