"""Strict checking of FOLD JSON before it is read: every field's type, every number finite and in range, every
array within the size limits, with the location of the first problem (``file_frames[2].vertices_coords[7][1]``).

:func:`load_fold_json` is the single entry, called by :func:`.fold.parse_fold` in place of ``json.loads``; once it
returns, the reader may index and convert without meeting a wrong type. What is checked:

* JSON itself: malformed text (line, column), nesting deeper than :data:`.limits.NESTING`; integers too long for
  a float (``1e400`` written out) become infinite, and like ``NaN``/``Infinity`` are refused where numbers go;
* sizes: every array at most :data:`.limits.FOLD_ENTRIES` entries;
* ``vertices_coords`` (and ``curved_fold:flat_coords``): arrays of 2 or 3 numbers (not strings, not ``true``),
  finite, within ±:data:`~.pattern.discretize.MAX_COORDINATE_MM` mm once ``frame_unit`` is applied;
* ``edges_vertices`` pairs and ``faces_vertices`` lists of integer indices (``1.5`` and ``true`` are not indices);
* ``edges_assignment`` strings; ``edges_foldAngle`` (and ``edges_foldAngles``, ``curved_fold:fold_angles``)
  numbers in [−180°, 180°] or null;
* ``file_frames`` objects with the same rules, ``frame_parent`` an integer, ``frame_inherit`` a boolean;
* our own ``curved_fold:`` fields: ``edge_polyline`` integer indices into ``sources`` (or the edges; −1 marks a
  triangulation diagonal), ``sources``
  and ``warnings`` strings, ``edge_from_curve`` booleans, ``mesh_type`` a string.

Index ranges against the vertex count and array lengths against each other are the reader's checks (it knows
which arrays belong together); this module guarantees they can be made.
"""

from __future__ import annotations

import json
import math
from typing import Any

from ..pattern.discretize import MAX_COORDINATE_MM
from ..pattern.model import PatternError
from . import limits

PREFIX = "curved_fold:"

LENGTH_UNITS_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "pt": 25.4 / 72.0, "um": 1e-3, "nm": 1e-6}
"""Scale of the units whose coordinates are range-checked in mm (others, like ``unit``, count as mm)."""

_INT_DIGITS = 18
"""JSON integers with more digits are read as floats (possibly infinite, then refused) instead of Python's
unbounded integers, which would overflow every later conversion."""


def _show(value: Any, width: int = 60) -> str:
    """``repr`` of a value, cut to ``width`` characters (a 300-digit number or a huge array stays one line)."""
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def _parse_int(text: str) -> int | float:
    return int(text) if len(text.lstrip("-")) <= _INT_DIGITS else float(text)


class _Checker:
    """Walks one FOLD object, raising :class:`PatternError` at the first problem (``src: location: problem``)."""

    def __init__(self, src: str) -> None:
        self.src = src
        self.max_entries = limits.FOLD_ENTRIES.value

    def fail(self, where: str, msg: str) -> PatternError:
        return PatternError(f"{self.src}: {where}{msg}")

    def array(self, value: Any, where: str) -> list:
        if not isinstance(value, list):
            raise self.fail(where, f" = {_show(value)} must be an array")
        if len(value) > self.max_entries:
            limits.FOLD_ENTRIES.check(len(value), f"{self.src}: {where}")
        return value

    @staticmethod
    def is_number(x: Any) -> bool:
        return type(x) in (int, float)

    def coords(self, value: Any, where: str, scale: float) -> None:
        rows = self.array(value, where)
        width = None
        bound = MAX_COORDINATE_MM / scale
        for i, row in enumerate(rows):
            if not isinstance(row, list) or len(row) not in (2, 3):
                raise self.fail(f"{where}[{i}]", f" = {_show(row)}: a vertex needs 2 or 3 coordinates")
            if width is None:
                width = len(row)
            elif len(row) != width:
                raise self.fail(f"{where}[{i}]", f" = {_show(row)}: every vertex needs the same 2 or 3 coordinates")
            for x in row:
                if not self.is_number(x):
                    raise self.fail(f"{where}[{i}]", f" = {_show(row)}: {_show(x)} is not a number")
                if not math.isfinite(x):
                    raise self.fail(f"{where}[{i}]", f" = {_show(row)} has a non-finite coordinate")
                if abs(x) > bound:
                    raise self.fail(
                        f"{where}[{i}]",
                        f" = {_show(row)}: coordinate {x:.3g} is beyond ±{MAX_COORDINATE_MM:g} mm (100 km); "
                        "check the file's frame_unit",
                    )

    def indices(self, value: Any, where: str, width: int | None) -> None:
        rows = self.array(value, where)
        for i, row in enumerate(rows):
            if not isinstance(row, list) or (width is not None and len(row) != width):
                want = f"{width} vertex indices" if width else "a list of vertex indices"
                raise self.fail(f"{where}[{i}]", f" = {_show(row)}: expected {want}")
            if len(row) > self.max_entries:
                limits.FOLD_ENTRIES.check(len(row), f"{self.src}: {where}[{i}]")
            for x in row:
                if type(x) is not int:
                    raise self.fail(f"{where}[{i}]", f" = {_show(row)}: {_show(x)} is not an integer index")
                if x < 0:
                    raise self.fail(f"{where}[{i}]", f" = {_show(row)}: index {x} is negative")

    def angles(self, value: Any, where: str) -> None:
        for i, x in enumerate(self.array(value, where)):
            if x is None:
                continue
            if not self.is_number(x) or not math.isfinite(x):
                raise self.fail(f"{where}[{i}]", f" = {_show(x)} is not a finite number of degrees (or null)")
            if not -180.0 <= x <= 180.0:
                raise self.fail(f"{where}[{i}]", f" = {x:g}° is outside [-180°, 180°]")

    def strings(self, value: Any, where: str) -> None:
        for i, x in enumerate(self.array(value, where)):
            if not isinstance(x, str):
                raise self.fail(f"{where}[{i}]", f" = {_show(x)} is not a string")

    def booleans(self, value: Any, where: str) -> None:
        for i, x in enumerate(self.array(value, where)):
            if not isinstance(x, bool) and not (type(x) is int and x in (0, 1)):
                raise self.fail(f"{where}[{i}]", f" = {_show(x)} is not true or false")

    def frame(self, obj: dict, where: str, scale: float, *, top: bool) -> None:
        """Check the fields one frame may carry (the key frame with ``top``, or one of ``file_frames``)."""
        for name in ("vertices_coords", PREFIX + "flat_coords"):
            if name in obj:
                self.coords(obj[name], where + name, scale)
        if "edges_vertices" in obj:
            self.indices(obj["edges_vertices"], where + "edges_vertices", 2)
        if "faces_vertices" in obj:
            self.indices(obj["faces_vertices"], where + "faces_vertices", None)
        if "edges_assignment" in obj:
            self.strings(obj["edges_assignment"], where + "edges_assignment")
        for name in ("edges_foldAngle", "edges_foldAngles", PREFIX + "fold_angles"):
            if name in obj:
                self.angles(obj[name], where + name)
        for name in ("frame_classes", "frame_attributes", "file_classes", PREFIX + "sources", PREFIX + "warnings"):
            if name in obj:
                self.strings(obj[name], where + name)
        if PREFIX + "edge_from_curve" in obj:
            self.booleans(obj[PREFIX + "edge_from_curve"], where + PREFIX + "edge_from_curve")
        for name in ("frame_unit", "file_creator", "file_author", "file_title", PREFIX + "mesh_type"):
            if name in obj and not isinstance(obj[name], str):
                raise self.fail(where + name, f" = {_show(obj[name])} is not a string")
        if PREFIX + "edge_polyline" in obj:
            name = PREFIX + "edge_polyline"
            values = self.array(obj[name], where + name)
            sources = obj.get(PREFIX + "sources")
            bound = len(sources) if isinstance(sources, list) and sources else len(values)
            for i, x in enumerate(values):
                if type(x) is not int or not -1 <= x < max(bound, 1):  # -1: a diagonal the triangulation added
                    what = f"{bound} sources" if isinstance(sources, list) and sources else f"{bound} edges"
                    raise self.fail(f"{where}{name}[{i}]", f" = {_show(x)} is not -1 or an index below {what}")
        if not top:
            if "frame_parent" in obj and type(obj["frame_parent"]) is not int:
                raise self.fail(where + "frame_parent", f" = {_show(obj['frame_parent'])} is not an integer")
            if "frame_inherit" in obj and not isinstance(obj["frame_inherit"], bool):
                raise self.fail(where + "frame_inherit", f" = {_show(obj['frame_inherit'])} is not true or false")

    def document(self, data: dict) -> None:
        unit = data.get("frame_unit", "unit")
        if not isinstance(unit, str):
            raise self.fail("frame_unit", f" = {_show(unit)} is not a string")
        scale = LENGTH_UNITS_MM.get(unit, 1.0)
        self.frame(data, "", scale, top=True)
        if "file_frames" in data:
            frames = self.array(data["file_frames"], "file_frames")
            for k, fr in enumerate(frames):
                if not isinstance(fr, dict):
                    raise self.fail(f"file_frames[{k}]", f" = {_show(fr)} is not an object")
                fr_unit = fr.get("frame_unit", unit)
                fr_scale = LENGTH_UNITS_MM.get(fr_unit, scale) if isinstance(fr_unit, str) else scale
                self.frame(fr, f"file_frames[{k}].", fr_scale, top=False)


def _depth(value: Any) -> int:
    """Deepest nesting of arrays and objects in a parsed JSON value (iterative: no recursion limit)."""
    deepest = 0
    stack = [(value, 1)]
    while stack:
        v, d = stack.pop()
        if isinstance(v, list):
            deepest = max(deepest, d)
            stack.extend((x, d + 1) for x in v if isinstance(x, (list, dict)))
        elif isinstance(v, dict):
            deepest = max(deepest, d)
            stack.extend((x, d + 1) for x in v.values() if isinstance(x, (list, dict)))
    return deepest


def load_fold_json(text: str | bytes, source: str) -> dict[str, Any]:
    """Parse FOLD JSON text and check it (see the module docstring); returns the JSON object.

    Raises :class:`PatternError` naming ``source`` and the location of the first problem.
    """
    try:
        data = json.loads(text, parse_int=_parse_int)
    except json.JSONDecodeError as exc:
        raise PatternError(f"{source}: malformed JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    except RecursionError:
        raise PatternError(
            f"{source}: nesting depth above the limit of {limits.NESTING.value} (set the environment variable "
            f"{limits.NESTING.variable} to raise it)"
        ) from None
    except ValueError as exc:  # bytes that are not UTF-8 text
        raise PatternError(f"{source}: {exc}") from None
    if not isinstance(data, dict):
        raise PatternError(f"{source}: a FOLD file must be a JSON object, not {type(data).__name__}")
    _Checker(source).document(data)  # first: it stops at the first over-long array without walking it
    limits.NESTING.check(_depth(data), source)
    return data
