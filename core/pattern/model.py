"""The crease-pattern model: what a designer drew, before and after discretisation (paper §3.1).

Two stages of the same pattern live here:

* :class:`CreaseCurve` — one drawn stroke (an SVG element, one spline of a Blender curve object) as a chain of
  exact segments (lines, cubic Béziers, elliptical arcs) with one role and one fold angle.
* :class:`CreasePattern` — the discretised pattern: vertices in the sheet's plane and straight segments, each with
  its assignment, target fold angle, the polyline (source stroke) it came from and whether it came from a curve.

Conventions used everywhere in the project:

* Lengths are millimetres, in the sheet's plane: x to the right, y up (SVG's y-down is flipped on import), so a
  pattern seen from +z looks as it does in the drawing program.
* Assignments are FOLD's: ``B`` border, ``M`` mountain, ``V`` valley, ``F`` facet (flat, angle 0), ``U`` undriven
  (free hinge, no target), ``C`` cut.
* Fold angles are degrees with FOLD's sign: valley > 0, mountain < 0, 0 flat, ±180 flat-folded. A valley folds
  towards +z (the viewer's side). ``nan`` means "no angle given" (the ``fold --angle`` option fills it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

ASSIGNMENTS = ("B", "M", "V", "F", "U", "C")
"""Every assignment a segment can carry (FOLD spec)."""

ASSIGNMENT_NAMES = {
    "B": "border",
    "M": "mountain",
    "V": "valley",
    "F": "facet",
    "U": "undriven",
    "C": "cut",
}


class PatternError(ValueError):
    """A crease pattern (or the file or curve it came from) is unusable.

    The message names the problem and where it is: which curve, which SVG element (with its line number), which
    FOLD array index.
    """


@dataclass(frozen=True)
class CurveSegment:
    """One exact piece of a drawn stroke, in millimetres.

    ``kind`` is ``"line"`` (``points`` = 2 end points), ``"cubic"`` (``points`` = 4 Bézier control points) or
    ``"arc"`` (``points`` = the two end points; ``arc`` = ``(cx, cy, rx, ry, phi, theta0, dtheta)``: centre, radii,
    x-axis rotation, start angle and signed sweep, all in radians, of the ellipse ``c + R(phi)·(rx cos t, ry sin t)``).
    """

    kind: str
    points: np.ndarray
    arc: tuple[float, float, float, float, float, float, float] | None = None

    def evaluate(self, t: np.ndarray | float) -> np.ndarray:
        """Points at parameters ``t`` in [0, 1] (shape ``(k, 2)``, or ``(2,)`` for a scalar)."""
        scalar = np.ndim(t) == 0
        t = np.atleast_1d(np.asarray(t, dtype=float))[:, None]
        p = self.points
        if self.kind == "line":
            out = (1.0 - t) * p[0] + t * p[1]
        elif self.kind == "cubic":
            s = 1.0 - t
            # Products only, no `**3`: numpy's power is not correctly rounded and its last bit depends on the numpy
            # version and the CPU (numpy 1.26 uses SVML on AVX-512, numpy 2 another kernel), which moved polyline
            # vertices by an ulp and changed meshes between Blender 4.5/5.0 (numpy 1.26) and 5.2 (numpy 2).
            out = s * s * s * p[0] + 3 * s * s * t * p[1] + 3 * s * t * t * p[2] + t * t * t * p[3]
        elif self.kind == "arc":
            cx, cy, rx, ry, phi, theta0, dtheta = self.arc
            a = theta0 + dtheta * t[:, 0]
            x, y = rx * np.cos(a), ry * np.sin(a)
            c, s_ = np.cos(phi), np.sin(phi)
            out = np.stack([cx + c * x - s_ * y, cy + s_ * x + c * y], axis=1)
        else:  # pragma: no cover - constructor callers use the three kinds only
            raise ValueError(f"unknown segment kind {self.kind!r}")
        return out[0] if scalar else out

    @property
    def start(self) -> np.ndarray:
        return self.evaluate(0.0)

    @property
    def end(self) -> np.ndarray:
        return self.evaluate(1.0)

    @property
    def is_straight(self) -> bool:
        """True for a line, or a cubic whose control points all lie on its chord (a straight Bézier)."""
        if self.kind == "line":
            return True
        if self.kind == "arc":
            return False
        p = self.points
        chord = p[3] - p[0]
        length = float(np.hypot(*chord))
        if length == 0.0:
            return bool(np.allclose(p, p[0]))
        cross = np.abs(chord[0] * (p[1:3, 1] - p[0, 1]) - chord[1] * (p[1:3, 0] - p[0, 0])) / length
        return bool(np.all(cross <= 1e-9 * max(length, 1.0)))


@dataclass
class CreaseCurve:
    """One drawn stroke: a chain of segments with one role and one fold angle.

    ``source`` names where it came from for messages, e.g. ``"SVG <path id='crease3'> (line 12)"`` or
    ``"curve 'Crease.001' spline 0"``. ``sampled``: the stroke's vertices were written by Curved Fold (its SVG
    export marks its polylines ``data-curved-fold="sampled"``) and are kept as they are: never thinned.
    """

    segments: list[CurveSegment]
    assignment: str
    fold_angle: float | None
    closed: bool = False
    source: str = ""
    sampled: bool = False

    @property
    def is_curved(self) -> bool:
        return any(not s.is_straight for s in self.segments)


@dataclass
class CreasePattern:
    """A discretised crease pattern: straight segments between vertices in the sheet's plane (mm).

    Arrays (``m`` segments, ``n`` vertices):

    * ``vertices`` ``(n, 2)`` float64
    * ``edges`` ``(m, 2)`` int64, vertex indices
    * ``assignments`` ``(m,)`` one-letter strings from :data:`ASSIGNMENTS`
    * ``fold_angles`` ``(m,)`` float64 degrees (FOLD sign), ``nan`` where none was given
    * ``edge_polyline`` ``(m,)`` int64, index into ``sources``: the stroke each segment came from
    * ``edge_from_curve`` ``(m,)`` bool: the segment discretises a curve (used by the ruling-aware swaps)

    ``sources`` describes each polyline (see :attr:`CreaseCurve.source`); ``warnings`` collects non-fatal
    problems met on the way (unknown SVG colours, capped tolerances, ...). ``interval`` is the discretisation interval
    (mm) a drawing was sampled at, nan for a pattern read as segments (a FOLD file, then the paper's default for its
    sheet applies): the triangulation splits long straight creases at it where they would fan needles
    (:mod:`..mesh.needles`); at an infinite interval it keeps every crease whole.
    """

    vertices: np.ndarray
    edges: np.ndarray
    assignments: np.ndarray
    fold_angles: np.ndarray
    edge_polyline: np.ndarray
    edge_from_curve: np.ndarray
    sources: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    interval: float = math.nan

    def __post_init__(self) -> None:
        self.vertices = np.asarray(self.vertices, dtype=np.float64).reshape(-1, 2)
        self.edges = np.asarray(self.edges, dtype=np.int64).reshape(-1, 2)
        self.assignments = np.asarray(self.assignments, dtype="<U1").reshape(-1)
        self.fold_angles = np.asarray(self.fold_angles, dtype=np.float64).reshape(-1)
        self.edge_polyline = np.asarray(self.edge_polyline, dtype=np.int64).reshape(-1)
        self.edge_from_curve = np.asarray(self.edge_from_curve, dtype=bool).reshape(-1)

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def n_edges(self) -> int:
        return len(self.edges)

    def count(self, assignment: str) -> int:
        """Number of segments with this assignment."""
        return int(np.count_nonzero(self.assignments == assignment))

    def bounding_box(self) -> tuple[np.ndarray, np.ndarray]:
        return self.vertices.min(axis=0), self.vertices.max(axis=0)

    @property
    def size(self) -> float:
        """Largest extent of the sheet (mm): the scale the default parameters follow."""
        lo, hi = self.bounding_box()
        return float(np.max(hi - lo))

    def validate(self) -> None:
        """Raise :class:`PatternError` if the arrays are inconsistent (lengths, indices, assignments, values)."""
        m = self.n_edges
        for name in ("assignments", "fold_angles", "edge_polyline", "edge_from_curve"):
            if len(getattr(self, name)) != m:
                raise PatternError(f"crease pattern: {name} has {len(getattr(self, name))} entries, edges has {m}")
        if m and (self.edges.min() < 0 or self.edges.max() >= self.n_vertices):
            bad = int(np.flatnonzero((self.edges < 0).any(1) | (self.edges >= self.n_vertices).any(1))[0])
            raise PatternError(
                f"crease pattern: edge {bad} refers to vertex {self.edges[bad].tolist()}, "
                f"but there are only {self.n_vertices} vertices"
            )
        unknown = sorted(set(self.assignments.tolist()) - set(ASSIGNMENTS))
        if unknown:
            raise PatternError(f"crease pattern: unknown assignment(s) {unknown}; expected one of {ASSIGNMENTS}")
        if not np.all(np.isfinite(self.vertices)):
            bad = int(np.flatnonzero(~np.isfinite(self.vertices).all(1))[0])
            raise PatternError(f"crease pattern: vertex {bad} has a non-finite coordinate {self.vertices[bad]}")
