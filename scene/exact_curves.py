"""The drawn geometry of an imported crease pattern, kept exactly on its curve objects (paper §3.1's input).

Blender stores curve control points in single precision and has no arc segments, so a pattern imported as Bézier
splines and read back is not the pattern the file describes: arcs become cubic pieces, straight lines pick up
float32 noise in their handles, and the discretisation (and with it the mesh and every figure) drifts away from
what the command line makes of the same file. The Import operator therefore groups the pattern into a handful of
objects (one per role and fold angle, one spline per chain of strokes joined end to end) and stores the file's own
description of every spline on the curve datablock (:data:`EXACT_KEY`, JSON): the strokes it chains, in file order,
as exact double-precision lines, cubics and arcs, with the fold angle and the import they came from.

When the add-on reads the curves back (:func:`exact_curves`), a spline whose control points are still the ones
the import wrote (to float32 precision) yields the stored strokes, transformed by the object's placement, so the
add-on and the command line discretise the same curves and build the same mesh. A spline that was edited yields
what Blender draws instead (the caller's Bézier path), so editing always wins.
"""

from __future__ import annotations

import json
import math
import uuid
from dataclasses import dataclass

import numpy as np

from ..core.pattern.model import CreaseCurve, CurveSegment, PatternError

EXACT_KEY = "cf_exact"
"""Custom property of a curve datablock holding the exact description of its splines (a JSON string)."""

FLOAT32_MATCH = 8.0 * float(np.finfo(np.float32).eps)
"""Relative tolerance (of the spline's largest coordinate) within which stored and actual control points agree:
a few float32 steps, far below any edit a designer makes."""

SIMILARITY_TOLERANCE = 1e-6
"""How far (relative) an object's 2D matrix may be from a rotation × uniform scale (± mirror) for the exact strokes
to follow it: a few float32 steps. A non-uniform scale or a shear is far beyond it (the Bézier is used)."""


@dataclass
class Stroke:
    """One stroke of the file inside a spline: its index in the file, where it came from, and its exact segments
    (as drawn, not as chained)."""

    index: int
    source: str
    closed: bool
    reversed: bool
    segments: list[CurveSegment]
    sampled: bool = False

    def oriented(self) -> list[CurveSegment]:
        """The segments in the spline's direction."""
        return reverse_segments(self.segments) if self.reversed else list(self.segments)


def reverse_segment(seg: CurveSegment) -> CurveSegment:
    """The same segment traversed the other way."""
    if seg.kind == "arc":
        cx, cy, rx, ry, phi, theta0, dtheta = seg.arc
        return CurveSegment("arc", seg.points[::-1].copy(), (cx, cy, rx, ry, phi, theta0 + dtheta, -dtheta))
    return CurveSegment(seg.kind, seg.points[::-1].copy(), seg.arc)


def reverse_segments(segments: list[CurveSegment]) -> list[CurveSegment]:
    return [reverse_segment(s) for s in reversed(segments)]


# ------------------------------------------------------------------------------------------------ chaining


def chain_strokes(curves: list[CreaseCurve], indices: list[int], quantum: float) -> list[list[tuple[int, bool]]]:
    """Chains of strokes joined end to end: lists of ``(index, reversed)``.

    Open strokes are chained through points where exactly two of them end (points equal to ``quantum`` mm); closed
    strokes and strokes whose ends meet stay alone. Chains start at a free end; what is left are loops.
    """

    def key(p: np.ndarray) -> tuple[int, int]:
        q = np.round(np.asarray(p, dtype=np.float64) / quantum)
        return int(q[0]), int(q[1])

    ends: dict[int, tuple[tuple[int, int], tuple[int, int]]] = {}
    at: dict[tuple[int, int], list[int]] = {}
    chains: list[list[tuple[int, bool]]] = []
    for i in indices:
        c = curves[i]
        a, b = key(c.segments[0].start), key(c.segments[-1].end)
        if c.closed or a == b:
            chains.append([(i, False)])
            continue
        ends[i] = (a, b)
        at.setdefault(a, []).append(i)
        at.setdefault(b, []).append(i)
    used: set[int] = set()

    def walk(i: int, node: tuple[int, int]) -> list[tuple[int, bool]]:
        chain = []
        while i is not None and i not in used:
            used.add(i)
            a, b = ends[i]
            rev = a != node
            chain.append((i, rev))
            node = a if rev else b
            nxt = [j for j in at[node] if j not in used]
            i = nxt[0] if len(at[node]) == 2 and nxt else None
        return chain

    for i in indices:  # file order: chains start at the first free end met
        if i in ends and i not in used:
            a, b = ends[i]
            if len(at[a]) != 2:
                chains.append(walk(i, a))
            elif len(at[b]) != 2:
                chains.append(walk(i, b))
    for i in indices:  # loops of open strokes
        if i in ends and i not in used:
            chains.append(walk(i, ends[i][0]))
    return chains


# ------------------------------------------------------------------------------------------------ control points


def _arc_cubics(seg: CurveSegment) -> list[np.ndarray]:
    """An elliptical arc as cubic Béziers, one per ≤ 90° piece, with the standard 4/3·tan(θ/4) handles."""
    cx, cy, rx, ry, phi, theta0, dtheta = seg.arc
    pieces = max(1, math.ceil(abs(dtheta) / (math.pi / 2) - 1e-9))
    c, s = math.cos(phi), math.sin(phi)
    rot = np.array([[c, s], [-s, c]])
    out = []
    for i in range(pieces):
        a0 = theta0 + dtheta * i / pieces
        a1 = theta0 + dtheta * (i + 1) / pieces
        h = 4.0 / 3.0 * math.tan((a1 - a0) / 4.0)
        unit = np.array(
            [
                [math.cos(a0), math.sin(a0)],
                [math.cos(a0) - h * math.sin(a0), math.sin(a0) + h * math.cos(a0)],
                [math.cos(a1) + h * math.sin(a1), math.sin(a1) - h * math.cos(a1)],
                [math.cos(a1), math.sin(a1)],
            ]
        )
        out.append((unit * np.array([rx, ry])) @ rot + np.array([cx, cy]))
    return out


def segment_cubics(seg: CurveSegment) -> list[np.ndarray]:
    """Control points (4×2, mm) of the cubic Bézier piece(s) drawing ``seg`` exactly (arcs: within 0.03 %)."""
    if seg.kind == "cubic":
        return [np.asarray(seg.points, dtype=np.float64)]
    if seg.kind == "line":
        a, b = np.asarray(seg.points, dtype=np.float64)
        return [np.array([a, a + (b - a) / 3.0, a + 2.0 * (b - a) / 3.0, b])]
    if seg.kind == "arc":
        return _arc_cubics(seg)
    raise PatternError(f"unknown segment kind {seg.kind!r}")


def knots(pieces: list[np.ndarray], cyclic: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bézier knots (``co``, ``handle_left``, ``handle_right``, 2D) of a chain of cubic pieces (4×2 each)."""
    n = len(pieces) if cyclic else len(pieces) + 1
    co = np.array([p[0] for p in pieces] + ([] if cyclic else [pieces[-1][3]]))
    right = np.array([p[1] for p in pieces] + ([] if cyclic else [pieces[-1][3]]))
    left = np.array([pieces[-1][2] if cyclic else pieces[0][0]] + [p[2] for p in pieces[: n - 1]])
    return co, left, right


def is_poly(segments: list[CurveSegment]) -> bool:
    """A chain of lines only: drawn as a Poly spline (lines stay lines)."""
    return all(s.kind == "line" for s in segments)


def poly_points(segments: list[CurveSegment], cyclic: bool) -> np.ndarray:
    """The points of a Poly spline through line segments (the closing point dropped when cyclic)."""
    pts = [s.points[0] for s in segments] + ([] if cyclic else [segments[-1].points[1]])
    return np.array(pts, dtype=np.float64)


# ------------------------------------------------------------------------------------------------ storage


def _segment_json(seg: CurveSegment) -> list:
    return [seg.kind, np.asarray(seg.points, dtype=np.float64).ravel().tolist(), list(seg.arc) if seg.arc else None]


def _segment_from_json(row: list) -> CurveSegment:
    kind, flat, arc = row
    return CurveSegment(kind, np.array(flat, dtype=np.float64).reshape(-1, 2), tuple(arc) if arc else None)


def new_import_id(name: str) -> str:
    """An id shared by every object of one import (curves of one import are read back in file order)."""
    return f"{name}#{uuid.uuid4().hex[:12]}"


def description(
    import_id: str,
    unit_scale: float,
    role: str,
    angle: float | None,
    splines: list[list[Stroke]],
) -> str:
    """The JSON stored under :data:`EXACT_KEY`: the import, its unit scale (BU per mm), the role and exact fold
    angle the import gave, and per spline its strokes."""
    return json.dumps(
        {
            "import": import_id,
            "unit_scale": float(unit_scale),
            "role": role,
            "angle": None if angle is None or not math.isfinite(angle) else float(angle),
            "splines": [
                [
                    {
                        "i": s.index,
                        "src": s.source,
                        "closed": s.closed,
                        "rev": s.reversed,
                        "sampled": s.sampled,
                        "segs": [_segment_json(g) for g in s.segments],
                    }
                    for s in strokes
                ]
                for strokes in splines
            ],
        },
        separators=(",", ":"),
    )


@dataclass
class Description:
    import_id: str
    unit_scale: float
    role: str
    angle: float | None
    splines: list[list[Stroke]]


def read_description(data) -> Description | None:
    """The stored description of a curve datablock, or ``None`` (none stored, or unreadable: then the drawn
    Bézier is used, which is always valid)."""
    text = data.get(EXACT_KEY) if hasattr(data, "get") else None
    if not isinstance(text, str):
        return None
    try:
        raw = json.loads(text)
        splines = [
            [
                Stroke(
                    int(s["i"]),
                    str(s["src"]),
                    bool(s["closed"]),
                    bool(s["rev"]),
                    [_segment_from_json(g) for g in s["segs"]],
                    bool(s.get("sampled", False)),
                )
                for s in strokes
            ]
            for strokes in raw["splines"]
        ]
        return Description(str(raw["import"]), float(raw["unit_scale"]), str(raw["role"]), raw["angle"], splines)
    except (ValueError, KeyError, TypeError):
        return None


# ------------------------------------------------------------------------------------------------ reading back


def expected_local(strokes: list[Stroke], cyclic: bool, poly: bool, unit_scale: float) -> np.ndarray:
    """The control points (local, Blender units, flattened 2D) the import wrote for a spline of these strokes."""
    segments = [g for s in strokes for g in s.oriented()]
    if poly:
        return poly_points(segments, cyclic) * unit_scale
    pieces = [p for g in segments for p in segment_cubics(g)]
    co, left, right = knots(pieces, cyclic)
    return np.concatenate([co, left, right]) * unit_scale


def unchanged(actual: np.ndarray, expected: np.ndarray) -> bool:
    """Stored and actual control points agree to float32 precision (the spline was not edited)."""
    if actual.shape != expected.shape:
        return False
    size = max(float(np.abs(expected).max(initial=0.0)), 1e-30)
    return bool(np.all(np.abs(actual - expected) <= FLOAT32_MATCH * size))


def similarity(matrix: np.ndarray, import_scale: float, unit_scale: float) -> np.ndarray | None:
    """The 2D map (3×3 homogeneous, mm → mm) that the object's world matrix makes of the stored strokes, or
    ``None`` if it is not a similarity in the XY plane (then the exact arcs cannot follow and Bézier is used)."""
    m = np.asarray(matrix, dtype=np.float64)
    a = m[:2, :2] * (import_scale / unit_scale)
    s2 = abs(float(np.linalg.det(a)))
    # an object's matrix is float32: rotations are orthogonal to ~1e-7, so "similarity" is judged at float32 level
    if s2 == 0.0 or abs(m[2, 0]) + abs(m[2, 1]) > SIMILARITY_TOLERANCE * math.sqrt(s2):
        return None
    gram = a.T @ a
    if not np.allclose(gram, s2 * np.eye(2), rtol=0.0, atol=SIMILARITY_TOLERANCE * s2):
        return None
    out = np.eye(3)
    out[:2, :2] = a
    out[:2, 2] = m[:2, 3] / unit_scale
    return out


def transform_segment(seg: CurveSegment, t: np.ndarray) -> CurveSegment:
    """``seg`` mapped by the similarity ``t`` (3×3): points moved, arcs re-centred, scaled, rotated or mirrored."""
    a, b = t[:2, :2], t[:2, 2]
    pts = seg.points @ a.T + b
    if seg.kind != "arc":
        return CurveSegment(seg.kind, pts, seg.arc)
    cx, cy, rx, ry, phi, theta0, dtheta = seg.arc
    s = math.sqrt(abs(float(np.linalg.det(a))))
    c = a @ np.array([cx, cy]) + b
    alpha = math.atan2(a[1, 0], a[0, 0])
    if np.linalg.det(a) > 0:
        arc = (float(c[0]), float(c[1]), rx * s, ry * s, phi + alpha, theta0, dtheta)
    else:  # a mirror: R(α)·F·R(φ)·diag(rx, ry)·(cos t, sin t) = R(α−φ)·diag(rx, ry)·(cos −t, sin −t)
        arc = (float(c[0]), float(c[1]), rx * s, ry * s, alpha - phi, -theta0, -dtheta)
    return CurveSegment("arc", pts, arc)


# ------------------------------------------------------------------------------------------------ FOLD imports

PATTERN_KEY = "cf_exact_pattern"
"""Custom property of the curve datablocks of a FOLD import: the file's discretised pattern (JSON), which the command
line folds as it is (no re-discretisation), so the unedited import folds to the same mesh."""


def pattern_json(import_id: str, objects: int, pattern, *, segments: bool = False) -> str:
    """The JSON stored under :data:`PATTERN_KEY`: the import, how many objects it made, the pattern's arrays, and
    whether they are another tool's segments that a fold samples at its interval (``segments``)."""
    angles = np.asarray(pattern.fold_angles, dtype=np.float64)
    return json.dumps(
        {
            "import": import_id,
            "objects": int(objects),
            "vertices": np.asarray(pattern.vertices, dtype=np.float64).ravel().tolist(),
            "edges": np.asarray(pattern.edges, dtype=np.int64).ravel().tolist(),
            "assignments": "".join(pattern.assignments.tolist()),
            "fold_angles": [None if not math.isfinite(a) else float(a) for a in angles.tolist()],
            "edge_polyline": np.asarray(pattern.edge_polyline, dtype=np.int64).tolist(),
            "edge_from_curve": [int(b) for b in np.asarray(pattern.edge_from_curve, dtype=bool).tolist()],
            "sources": list(pattern.sources),
            "segments": bool(segments),
        },
        separators=(",", ":"),
    )


@dataclass
class StoredPattern:
    import_id: str
    objects: int
    arrays: dict

    @property
    def segments(self) -> bool:
        """Another tool's segments, sampled by each fold at its interval (imports before this field: sampled)."""
        return bool(self.arrays.get("segments", False))


def read_pattern_json(data) -> StoredPattern | None:
    """The stored FOLD pattern of a curve datablock, or ``None``."""
    text = data.get(PATTERN_KEY) if hasattr(data, "get") else None
    if not isinstance(text, str):
        return None
    try:
        raw = json.loads(text)
        return StoredPattern(str(raw["import"]), int(raw["objects"]), raw)
    except (ValueError, KeyError, TypeError):
        return None


def pattern_from_json(stored: StoredPattern, transform: np.ndarray | None):
    """The stored :class:`CreasePattern`, its vertices moved by ``transform`` (``None``: exactly as stored)."""
    from ..core.pattern.model import CreasePattern

    raw = stored.arrays
    vertices = np.array(raw["vertices"], dtype=np.float64).reshape(-1, 2)
    if transform is not None:
        vertices = vertices @ transform[:2, :2].T + transform[:2, 2]
    pattern = CreasePattern(
        vertices=vertices,
        edges=np.array(raw["edges"], dtype=np.int64).reshape(-1, 2),
        assignments=np.array(list(raw["assignments"]), dtype="<U1"),
        fold_angles=np.array([np.nan if a is None else a for a in raw["fold_angles"]], dtype=np.float64),
        edge_polyline=np.array(raw["edge_polyline"], dtype=np.int64),
        edge_from_curve=np.array(raw["edge_from_curve"], dtype=bool),
        sources=[str(s) for s in raw["sources"]],
    )
    pattern.validate()
    return pattern
