"""Pins and glue: holding a fold the way hands or glue do (issue 17; the paper's future work, "handling the shape
with control points and gluing some points on the surface together increases the range of shapes").

* A **pin** holds a vertex of the sheet at a target position (mm), or where it starts when no target is given (the
  flat sheet for a fold from flat, the current shape for a warm start). The fast solver treats pinned vertices as
  fixed degrees of freedom (``core.solve.newton``), not stiff springs, so a pinned vertex sits exactly on its target
  and Newton's convergence stays quadratic.
* **Glue** joins two vertices with a zero-length bar (``core.solve.model.with_glue``) of stiffness
  :data:`GLUE_STIFFNESS`: the pair is pulled together (close a cylinder, join a box corner) and the distance left at
  equilibrium is the reported gap.

Two forms: :class:`ConstraintSpec` names points by their flat position in the pattern (what a user can write before
the mesh exists: the command line's ``curved_fold:pins``/``curved_fold:glue`` FOLD fields or a JSON file beside the
pattern, read by :mod:`..io.constraints_file`), :class:`Constraints` holds mesh vertex indices (what the solver
uses; Blender's vertex groups give these directly). :meth:`ConstraintSpec.resolve` maps one onto the other.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..mesh.fold_mesh import FoldMesh
from ..pattern.discretize import MAX_COORDINATE_MM
from ..pattern.model import PatternError

GLUE_STIFFNESS = 1e6
"""Stiffness of a glue bar in the normalised model (sheet in a unit sphere; a crease is about 1 per unit length). The
gap left is the force holding the pair apart divided by this. Measured on an eight-panel strip rolled shut against
creases 5° short of closing: 1e5 leaves 5e-8 of the diagonal in 23 Newton iterations (1e4: 5e-7, 20; 1e6: 5e-9, 34;
1e9: 6e-11 but 190 iterations, the stiff bar slows the damped Newton steps)."""

SNAP_REL = 1e-3
"""A pin or glue point must lie within this fraction of the sheet's diagonal of a mesh vertex."""

PINS_FIELD = "curved_fold:pins"
GLUE_FIELD = "curved_fold:glue"
SIDECAR_SUFFIX = ".constraints.json"
"""``pattern.svg`` → ``pattern.constraints.json`` beside it is read by the ``fold`` command when present."""


@dataclass
class Constraints:
    """Pins and glue on mesh vertex indices.

    ``pins`` ``(p,)`` vertex indices; ``pin_targets`` ``(p, 3)`` mm, a row of ``nan`` = stay where it starts;
    ``glue`` ``(g, 2)`` vertex pairs pulled together."""

    pins: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    pin_targets: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    glue: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))

    def __post_init__(self) -> None:
        self.pins = np.asarray(self.pins, dtype=np.int64).reshape(-1)
        targets = np.asarray(self.pin_targets, dtype=np.float64)
        if targets.size == 0:
            targets = np.full((len(self.pins), 3), np.nan)
        self.pin_targets = targets.reshape(-1, 3)
        self.glue = np.asarray(self.glue, dtype=np.int64).reshape(-1, 2)
        if len(self.pin_targets) != len(self.pins):
            raise PatternError(f"{len(self.pins)} pins but {len(self.pin_targets)} pin targets")

    @property
    def empty(self) -> bool:
        return len(self.pins) == 0 and len(self.glue) == 0

    def check(self, n_vertices: int) -> None:
        """Raise :class:`PatternError` for indices outside the mesh, a vertex pinned twice or glued to itself."""
        for name, idx in (("pin", self.pins), ("glue", self.glue.reshape(-1))):
            bad = idx[(idx < 0) | (idx >= n_vertices)]
            if len(bad):
                raise PatternError(f"{name} vertex {int(bad[0])} is not in the mesh ({n_vertices} vertices)")
        if len(np.unique(self.pins)) != len(self.pins):
            raise PatternError("a vertex is pinned twice")
        if np.any(self.glue[:, 0] == self.glue[:, 1]):
            raise PatternError("a vertex is glued to itself")
        if not np.all(np.isfinite(self.pin_targets) | np.isnan(self.pin_targets)):
            raise PatternError("pin targets must be finite (or left out to pin a vertex where it is)")

    def fixed_mask(self, n_vertices: int) -> np.ndarray:
        """``(n, 3)`` bool: the solver's fixed degrees of freedom (every coordinate of a pinned vertex)."""
        mask = np.zeros((n_vertices, 3), dtype=bool)
        mask[self.pins] = True
        return mask

    def place_pins(self, positions: np.ndarray) -> np.ndarray:
        """``positions`` ``(n, 3)`` mm with pinned vertices moved to their targets (those without stay)."""
        out = np.array(positions, dtype=np.float64)
        has = np.all(np.isfinite(self.pin_targets), axis=1)
        out[self.pins[has]] = self.pin_targets[has]
        return out

    def holds_pose_only(self, mesh: FoldMesh) -> bool:
        """Whether the pins can only place the sheet, not bend it: no glue, and every pinned vertex is a corner of
        one triangle (a corner held on the table, a face fixed as Origami Simulator fixes one). A triangle is rigid
        to within its strain, so such pins choose the fold's pose and nothing else: the solver folds the sheet free
        and poses it (:meth:`pose`), instead of making Newton swing the whole sheet about a small anchor."""
        if len(self.glue) or not 0 < len(self.pins) <= 3:
            return False
        return bool(np.any(np.isin(mesh.triangles, self.pins).sum(axis=1) == len(self.pins)))

    def pose(self, positions: np.ndarray, start: np.ndarray, exact: bool = False) -> np.ndarray:
        """``positions`` ``(n, 3)`` mm moved rigidly so that the pinned vertices come closest to their targets
        (where they are in ``start`` for pins without a target), by the best rigid fit (:func:`rigid_fit`), with
        ``exact`` the pinned vertices then put on them."""
        p = np.asarray(positions, dtype=np.float64)
        targets = self.place_pins(start)[self.pins]
        rot, shift = rigid_fit(p[self.pins], targets)
        out = p @ rot + shift
        if exact:
            out[self.pins] = targets
        return out

    def gaps(self, positions: np.ndarray) -> np.ndarray:
        """Distance (mm) between each glued pair at ``positions``."""
        p = np.asarray(positions, dtype=np.float64)
        return np.linalg.norm(p[self.glue[:, 1]] - p[self.glue[:, 0]], axis=1)

    def report(self, mesh: FoldMesh, positions: np.ndarray, start: np.ndarray | None = None) -> dict[str, Any]:
        """The report's constraint figures: counts, the largest glue gap (mm and ÷ diagonal), the largest distance
        of a pinned vertex from its target (mm; from ``start`` for pins without a target)."""
        p = np.asarray(positions, dtype=np.float64)
        out: dict[str, Any] = {"pins": len(self.pins), "glue": len(self.glue)}
        if len(self.glue):
            gap = float(self.gaps(p).max())
            out["glue_gap_max_mm"] = gap
            out["glue_gap_rel"] = gap / max(mesh.diagonal, 1e-300)
        if len(self.pins):
            reference = self.place_pins(mesh.vertices_3d if start is None else start)
            out["pin_error_max_mm"] = float(np.linalg.norm(p[self.pins] - reference[self.pins], axis=1).max())
        return out


def rigid_fit(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rigid motion (rotation without reflection, then translation) that takes points ``a`` ``(m, 3)`` closest
    to ``b`` in the least-squares sense (Kabsch): ``(rot, shift)`` with ``a @ rot + shift ≈ b``. One point gives a
    translation, two leave the turn about their line as the SVD gives it."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    ac, bc = a.mean(axis=0), b.mean(axis=0)
    u, _, vt = np.linalg.svd((a - ac).T @ (b - bc))
    d = np.sign(np.linalg.det(u @ vt)) or 1.0
    rot = u @ np.diag([1.0, 1.0, d]) @ vt
    return rot, bc - ac @ rot


@dataclass
class ConstraintSpec:
    """Pins and glue named by flat points of the pattern (mm, the pattern's own coordinates; an SVG's y is flipped:
    pattern y = −SVG y).

    ``pins``: ``[(point, target or None), ...]`` with ``point`` ``(x, y)`` and ``target`` ``(x, y, z)`` mm;
    ``glue``: ``[(point, point), ...]``."""

    pins: list[tuple[tuple[float, float], tuple[float, float, float] | None]] = field(default_factory=list)
    glue: list[tuple[tuple[float, float], tuple[float, float]]] = field(default_factory=list)
    source: str = ""

    @property
    def empty(self) -> bool:
        return not self.pins and not self.glue

    def resolve(self, mesh: FoldMesh) -> Constraints:
        """Mesh vertex indices of the points (the nearest vertex, within :data:`SNAP_REL` of the diagonal)."""

        def vertex(point: tuple[float, float], what: str) -> int:
            d = np.linalg.norm(mesh.vertices - np.asarray(point, dtype=np.float64), axis=1)
            k = int(np.argmin(d))
            if d[k] > SNAP_REL * mesh.diagonal:
                raise PatternError(
                    f"{self.source or 'constraints'}: {what} point ({point[0]:g}, {point[1]:g}) is not a vertex of the "
                    f"meshed sheet (nearest vertex {d[k]:.3g} mm away); use a crease end or a border corner "
                    "(pattern coordinates: y up, an SVG's y negated)"
                )
            return k

        pins = [vertex(p, "pin") for p, _ in self.pins]
        targets = [(np.nan, np.nan, np.nan) if t is None else t for _, t in self.pins]
        glue = [(vertex(a, "glue"), vertex(b, "glue")) for a, b in self.glue]
        where = self.source or "constraints"

        def at(k: int) -> str:
            x, y = mesh.vertices[k]
            return f"({x:g}, {y:g})"

        # named here, with the file and the entries: Constraints.check said only "a vertex is pinned twice"
        first: dict[int, int] = {}
        for k, v in enumerate(pins):
            if v in first:
                raise PatternError(f"{where}: pins {first[v]} and {k} are the same vertex {at(v)}")
            first[v] = k
        for k, (a, b) in enumerate(glue):
            if a == b:
                raise PatternError(f"{where}: glue {k} joins the vertex {at(a)} to itself (its two points snap to it)")
        out = Constraints(np.array(pins, dtype=np.int64), np.array(targets, dtype=np.float64).reshape(-1, 3), glue)
        out.check(mesh.n_vertices)
        return out


def _point(value: Any, size: int, what: str, source: str) -> tuple[float, ...]:
    try:
        p = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        p = ()
    if len(p) != size or not all(np.isfinite(p)):
        raise PatternError(f"{source}: {what} must be {size} finite numbers, got {_short(value)}")
    if max(abs(v) for v in p) > MAX_COORDINATE_MM:  # a pin target at 1e300 folded to nan and was written out
        raise PatternError(f"{source}: {what} {_short(value)} is beyond ±{MAX_COORDINATE_MM:g} mm")
    return p


def _short(value: Any) -> str:
    """``value`` as a message quotes it: its repr, cut to 80 characters."""
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def parse_constraints(data: dict[str, Any], source: str = "constraints") -> ConstraintSpec:
    """A :class:`ConstraintSpec` from a dict with ``curved_fold:pins`` / ``curved_fold:glue`` (or ``pins``/``glue``).

    ``pins``: a list of ``[x, y]`` (pin where it is) or ``{"point": [x, y], "target": [x, y, z]}``;
    ``glue``: a list of ``[[x1, y1], [x2, y2]]``. Raises :class:`PatternError` (one clear line) on anything else."""
    if not isinstance(data, dict):
        raise PatternError(f"{source}: expected a JSON object with 'pins' and/or 'glue'")
    pins_raw = data.get(PINS_FIELD, data.get("pins", [])) or []
    glue_raw = data.get(GLUE_FIELD, data.get("glue", [])) or []
    if not isinstance(pins_raw, list) or not isinstance(glue_raw, list):
        raise PatternError(f"{source}: 'pins' and 'glue' must be lists")
    spec = ConstraintSpec(source=source)
    for k, item in enumerate(pins_raw):
        if isinstance(item, dict):
            point = _point(item.get("point"), 2, f"pin {k} point", source)
            target = item.get("target")
            spec.pins.append((point, None if target is None else _point(target, 3, f"pin {k} target", source)))
        else:
            spec.pins.append((_point(item, 2, f"pin {k}", source), None))
    for k, item in enumerate(glue_raw):
        if not isinstance(item, list | tuple) or len(item) != 2:
            raise PatternError(f"{source}: glue {k} must be a pair of points [[x1, y1], [x2, y2]], got {item!r}")
        spec.glue.append((_point(item[0], 2, f"glue {k}", source), _point(item[1], 2, f"glue {k}", source)))
    return spec
