"""FOLD files (https://github.com/edemaine/fold, spec 1.1/1.2): read crease patterns and folded states, write both.

Reading (:func:`read_fold`, then :func:`fold_to_pattern` or :func:`fold_to_mesh`): ``vertices_coords`` (2D, or 3D
lying in one axis plane, which counts as flat: Origami Simulator stores patterns as (x, 0, y); a folded 3D key frame
is read as a frame), ``edges_vertices``, ``edges_assignment`` (lowercase accepted, FOLD 1.2's ``J`` join edges
dropped), ``edges_foldAngle`` in degrees (the v1.0 spelling ``edges_foldAngles`` too), ``faces_vertices``,
``file_frames`` (with ``frame_parent``/``frame_inherit``) and ``frame_unit``. Coincident vertices are merged along
slits or refused before any triangulation sees them. Every problem raises :class:`~.pattern.PatternError` naming the
array and index.

Writing is atomic (:mod:`.atomic`) and follows the spec's conventions (every fold angle a number, 0 for borders and
flat edges). :func:`write_pattern_fold` stores a discretised pattern (2D, ``creasePattern``, mm) with our own
``curved_fold:`` fields (source polyline, from-curve flag, sources), so SVG → pattern → FOLD → pattern is lossless
(floats are written with ``repr`` precision). :func:`write_folded_fold` stores a folded mesh: the crease pattern
(triangles as faces) as the key frame, each folded state as a ``foldedForm`` frame in ``file_frames``; our own files
read back to the same mesh (:func:`fold_to_mesh`) and the same pattern (:func:`fold_to_pattern`). See docs/formats.md.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Generator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .. import run_to_end
from ..mesh.fold_mesh import FoldMesh, corner_angles, polygon_sides
from ..pattern.discretize import segments_at_interval, with_crossings_split
from ..pattern.model import ASSIGNMENTS, CreasePattern, PatternError
from ..pattern.polylines import drawn_strokes
from .atomic import atomic_write_text
from .fold_validate import load_fold_json

UNIT_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "pt": 25.4 / 72.0, "um": 1e-3, "nm": 1e-6, "unit": 1.0}
"""Millimetres per FOLD ``frame_unit``; ``unit`` (unitless, the FOLD default) is taken as millimetres."""

UNITLESS_SMALL_MM = 10.0
"""A unitless file (``frame_unit`` ``unit`` or none) whose sheet, read as millimetres, is smaller than this gets a
warning: Rabbit Ear and the FOLD spec's examples draw a unit square, which folded silently into a 1 mm model (a
0.7 mm STL; a designer session, fifteenth pass)."""

FOLD_ASSIGNMENTS = (*ASSIGNMENTS, "J")
"""Assignments a FOLD file may carry: ours plus FOLD 1.2's ``J`` (join: an edge drawn only for modelling, e.g. a
triangulation diagonal; the faces on both sides are one face, so :func:`fold_to_pattern` drops it)."""

PREFIX = "curved_fold:"
CREATOR = "Curved Fold (Blender extension)"


@dataclass
class FoldDocument:
    """A FOLD file, checked and converted to arrays (lengths in mm).

    ``vertices`` are the flat 2D positions: the file's own coordinates when flat, else ``curved_fold:flat_coords``
    (None when a folded file does not carry them). ``frames`` are the 3D positions of every folded frame (key frame
    first, then ``file_frames`` in order, inheritance resolved); empty for a flat crease pattern.
    """

    data: dict[str, Any]
    vertices: np.ndarray | None
    edges: np.ndarray
    assignments: np.ndarray
    fold_angles: np.ndarray
    faces: list[list[int]]
    frames: list[np.ndarray] = field(default_factory=list)
    frame_fold_angles: list[np.ndarray | None] = field(default_factory=list)
    unit: str = "mm"
    source_name: str = ""
    warnings: list[str] = field(default_factory=list)


def _fail(source: str, msg: str) -> PatternError:
    return PatternError(f"{source}: {msg}")


def _coords(value: Any, name: str, source: str, scale: float) -> np.ndarray:
    if not isinstance(value, list):
        raise _fail(source, f"{name} must be an array of coordinate arrays")
    dims = {len(v) if isinstance(v, list) else -1 for v in value}
    if value and (len(dims) != 1 or dims.pop() not in (2, 3)):
        bad = next(i for i, v in enumerate(value) if not isinstance(v, list) or len(v) != len(value[0]))
        raise _fail(source, f"{name}[{bad}] = {value[bad]!r}: every vertex needs the same 2 or 3 coordinates")
    try:
        arr = np.array(value, dtype=float).reshape(len(value), -1) if value else np.zeros((0, 2))
    except (TypeError, ValueError):
        bad = next(
            i
            for i, v in enumerate(value)
            if not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)
        )
        raise _fail(source, f"{name}[{bad}] = {value[bad]!r} is not a list of numbers") from None
    finite = np.isfinite(arr).all(axis=1)
    if not finite.all():
        bad = int(np.flatnonzero(~finite)[0])
        raise _fail(source, f"{name}[{bad}] = {value[bad]!r} has a non-finite coordinate")
    return arr * scale


def _index_array(value: Any, name: str, source: str, width: int | None, limit: int, target: str) -> list[list[int]]:
    if not isinstance(value, list):
        raise _fail(source, f"{name} must be an array")
    out = []
    for i, row in enumerate(value):
        if not isinstance(row, list) or (width is not None and len(row) != width):
            want = f"{width} vertex indices" if width else "a list of vertex indices"
            raise _fail(source, f"{name}[{i}] = {row!r}: expected {want}")
        for x in row:
            if not isinstance(x, int) or isinstance(x, bool):
                raise _fail(source, f"{name}[{i}] = {row!r}: {x!r} is not an integer index")
            if x < 0 or x >= limit:
                raise _fail(source, f"{name}[{i}] = {row!r}: index {x} out of range ({limit} {target})")
        out.append(row)
    return out


def _check_length(data: dict, name: str, expected: int, ref: str, source: str) -> None:
    if name in data and len(data[name]) != expected:
        raise _fail(source, f"{name} has {len(data[name])} entries but {ref} has {expected}")


def _angles(value: Any, name: str, source: str) -> np.ndarray:
    out = np.full(len(value), np.nan)
    for i, x in enumerate(value):
        if x is None:
            continue
        if not isinstance(x, (int, float)) or isinstance(x, bool) or not math.isfinite(x):
            raise _fail(source, f"{name}[{i}] = {x!r} is not a finite number of degrees (or null)")
        out[i] = float(x)
    return out


def _roles_sign_angles(angles: np.ndarray, assign: np.ndarray, src: str, warnings: list[str]) -> None:
    """Give mountains negative and valleys positive fold angles (the FOLD spec's signs), in place, with a warning
    naming the edges whose sign said the other: a valley at −180° was folded as a mountain without a word (a CLI
    review session). The assignment is what the drawing shows and what an SVG's colour gives; a tool that writes
    mountains positive gets the fold its colours ask for."""
    wrong = np.flatnonzero(((assign == "V") & (angles < 0)) | ((assign == "M") & (angles > 0)))
    if not len(wrong):
        return
    k = int(wrong[0])
    more = f" and {len(wrong) - 1} more" if len(wrong) > 1 else ""
    warnings.append(
        f"{src}: edges_foldAngle[{k}] = {angles[k]:g} on a {'valley' if assign[k] == 'V' else 'mountain'} "
        f"(edges_assignment {assign[k]}){more}: FOLD folds valleys positive and mountains negative; folded as "
        "the assignment says"
    )
    angles[wrong] = -angles[wrong]


def parse_fold(text: str, source_name: str = "<fold>") -> FoldDocument:
    """Check and convert FOLD JSON text (see :class:`FoldDocument`)."""
    src = source_name
    data = load_fold_json(text, src)  # strict types, ranges and size limits, with locations (fold_validate.py)
    warnings: list[str] = []
    unit = str(data.get("frame_unit", "unit"))
    if unit not in UNIT_MM:
        warnings.append(f"{src}: unknown frame_unit {unit!r}, coordinates taken as millimetres")
    scale = UNIT_MM.get(unit, 1.0)
    if "edges_foldAngles" in data and "edges_foldAngle" not in data:
        data["edges_foldAngle"] = data.pop("edges_foldAngles")
    for name in ("vertices_coords", "edges_vertices", "edges_assignment"):
        if name not in data:
            raise _fail(src, f"missing required array {name}")
    coords = _coords(data["vertices_coords"], "vertices_coords", src, scale)
    n = len(coords)
    edges = _index_array(data["edges_vertices"], "edges_vertices", src, 2, n, "vertices")
    m = len(edges)
    for name in ("edges_assignment", "edges_foldAngle", PREFIX + "edge_polyline", PREFIX + "edge_from_curve"):
        if name in data and not isinstance(data[name], list):
            raise _fail(src, f"{name} must be an array")
        _check_length(data, name, m, "edges_vertices", src)
    assignments = []
    for i, a in enumerate(data["edges_assignment"]):
        s = a.upper() if isinstance(a, str) else a
        if s not in FOLD_ASSIGNMENTS:
            raise _fail(src, f"edges_assignment[{i}] = {a!r} is not one of {', '.join(FOLD_ASSIGNMENTS)}")
        assignments.append(s)
    assign = np.array(assignments, dtype="<U1")
    if "edges_foldAngle" in data:
        angles = _angles(data["edges_foldAngle"], "edges_foldAngle", src)
        _roles_sign_angles(angles, assign, src, warnings)
    else:
        angles = np.where(assign == "F", 0.0, np.nan)
    faces = []
    if "faces_vertices" in data:
        faces = _index_array(data["faces_vertices"], "faces_vertices", src, None, n, "vertices")
        short = next((i for i, f in enumerate(faces) if len(f) < 3), None)
        if short is not None:  # a polygon has three corners at least (an empty face broke the cut detection)
            raise _fail(src, f"faces_vertices[{short}] = {faces[short]!r}: a face needs at least 3 vertices")
    extent = float(np.max(np.ptp(coords, axis=0))) if n else 0.0
    if unit == "unit" and 0.0 < extent < UNITLESS_SMALL_MM:
        given = 'frame_unit "unit"' if "frame_unit" in data else "no frame_unit"
        warnings.append(
            f"{src}: {given} (unitless coordinates, read as millimetres): the sheet is {extent:.3g} mm across; "
            "scale the file for a real size (the folded shape is the same at any size)"
        )
    flat_key = PREFIX + "flat_coords"
    frames: list[np.ndarray] = []
    frame_angles: list[np.ndarray | None] = []
    key_plane = flat_plane(coords, extent)
    key_is_flat = key_plane is not None
    if flat_key in data:
        flat = _coords(data[flat_key], flat_key, src, scale)
        if len(flat) != n:
            raise _fail(src, f"{flat_key} has {len(flat)} entries but vertices_coords has {n}")
        flat = flat[:, :2]
    elif key_plane is not None:
        flat = key_plane
    else:
        flat = None
    fa_key = PREFIX + "fold_angles"

    def frame_angles_of(fr: dict, where: str) -> np.ndarray | None:
        if fa_key not in fr:
            # a frame's own edges_foldAngle is its folded state's angles (the key frame's are the targets)
            own = fr.get("edges_foldAngle") if fr is not data else None
            return _angles(own, where + "edges_foldAngle", src) if isinstance(own, list) and len(own) == m else None
        if not isinstance(fr[fa_key], list) or len(fr[fa_key]) != m:
            got = len(fr[fa_key]) if isinstance(fr[fa_key], list) else "not an array"
            raise _fail(src, f"{where}{fa_key} has {got} entries but edges_vertices has {m}")
        return _angles(fr[fa_key], where + fa_key, src)

    if not key_is_flat:
        frames.append(coords.copy())
        frame_angles.append(frame_angles_of(data, ""))
    sub = data.get("file_frames", [])
    if not isinstance(sub, list):
        raise _fail(src, "file_frames must be an array of frame objects")
    resolved: list[dict] = [data]
    for k, fr in enumerate(sub):
        where = f"file_frames[{k}]."
        if not isinstance(fr, dict):
            raise _fail(src, f"file_frames[{k}] is not an object")
        merged = dict(fr)
        if fr.get("frame_inherit"):
            parent = fr.get("frame_parent", 0)
            if not isinstance(parent, int) or parent < 0 or parent > k:
                raise _fail(
                    src, f"{where}frame_parent = {parent!r} must refer to the key frame (0) or an earlier frame"
                )
            merged = {**resolved[parent], **fr}
        resolved.append(merged)
        if "vertices_coords" not in merged:
            continue
        fc = _coords(merged["vertices_coords"], where + "vertices_coords", src, scale)
        if len(fc) != n:
            raise _fail(src, f"{where}vertices_coords has {len(fc)} entries but vertices_coords has {n}")
        if fc.shape[1] == 2:
            fc = np.column_stack([fc, np.zeros(n)])
        same_edges = "edges_vertices" not in fr or fr["edges_vertices"] == data["edges_vertices"]
        plane = flat_plane(fc, float(np.max(np.ptp(fc, axis=0)))) if flat is None and same_edges else None
        if plane is not None:  # a folded key frame with its crease pattern in a frame of its own
            flat = plane
            continue
        frames.append(fc)
        frame_angles.append(frame_angles_of(fr, where) if fa_key not in merged else frame_angles_of(merged, where))
    return FoldDocument(
        data=data,
        vertices=flat,
        edges=np.array(edges, dtype=np.int64).reshape(-1, 2),
        assignments=assign,
        fold_angles=angles,
        faces=faces,
        frames=frames,
        frame_fold_angles=frame_angles,
        unit=unit,
        source_name=src,
        warnings=warnings,
    )


def read_fold(path: str | os.PathLike[str]) -> FoldDocument:
    """Read and check a FOLD file (see :func:`parse_fold`)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise PatternError(f"{p}: cannot read FOLD file: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise PatternError(f"{p.name}: not UTF-8 text (byte {exc.start})") from None
    return parse_fold(text, p.name)


def flat_plane(coords: np.ndarray, extent: float | None = None) -> np.ndarray | None:
    """The 2D sheet coordinates of vertex positions that lie in one axis plane, else None (a folded state).

    2D coordinates are returned as they are. 3D coordinates are flat when one axis is constant (to 1e-7 of the
    extent): z constant gives (x, y); y constant (Origami Simulator stores a crease pattern as (x, 0, y_svg), y up)
    gives (x, −z), the pattern as drawn in its SVG seen from above; x constant gives (y, z). Each mapping is a
    rotation of the plane's own axes, so a valley stays a valley.
    """
    coords = np.asarray(coords, dtype=np.float64)
    if coords.ndim != 2 or not len(coords):
        return np.zeros((0, 2)) if coords.ndim == 2 else None
    if coords.shape[1] == 2:
        return coords.copy()
    span = np.ptp(coords, axis=0)
    size = float(extent) if extent is not None else float(span.max())
    tol = 1e-7 * max(size, 1.0)
    for axis, (a, b, sign) in ((2, (0, 1, 1.0)), (1, (0, 2, -1.0)), (0, (1, 2, 1.0))):
        if span[axis] <= tol:
            return np.column_stack([coords[:, a], sign * coords[:, b]])
    return None


def cut_mask(
    vertices: np.ndarray, edges: np.ndarray, assignments: np.ndarray, faces: list | np.ndarray | None = None
) -> np.ndarray:
    """Which border (``B``) edges are really cuts: a border edge with a face on both sides (a slit whose tips were
    not split) or lying on another border edge (a slit split into two borders, as our meshes store cuts).

    Used to give cuts back their role when reading our folded files and when drawing a mesh's crease pattern."""
    vertices = np.asarray(vertices, dtype=np.float64)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    border = np.asarray(assignments) == "B"
    out = np.zeros(len(edges), dtype=bool)
    if not border.any():
        return out
    n = max(len(vertices), 1)
    pairs = np.sort(edges, axis=1)
    keys = pairs[:, 0] * n + pairs[:, 1]
    if faces is not None and len(faces):
        if isinstance(faces, np.ndarray) or len({len(f) for f in faces}) == 1:  # triangles: one array, no loop
            rect = np.asarray(faces, dtype=np.int64)
            sides = [polygon_sides(rect)]
        else:
            sides = [
                np.sort(np.column_stack([f, np.roll(f, -1)]), axis=1) for f in map(np.asarray, faces) if len(f) > 1
            ]
        s = np.concatenate(sides) if sides else np.zeros((0, 2), dtype=np.int64)
        if len(s):
            side_keys, counts = np.unique(s[:, 0] * n + s[:, 1], return_counts=True)
            at = np.clip(np.searchsorted(side_keys, keys), 0, len(side_keys) - 1)
            out |= border & (side_keys[at] == keys) & (counts[at] >= 2)
    size = float(np.ptp(vertices, axis=0).max()) if len(vertices) else 1.0
    grid = np.round(vertices / (1e-9 * (size or 1.0))).astype(np.int64)
    a, c = grid[edges[:, 0]], grid[edges[:, 1]]
    swap = (a[:, 0] > c[:, 0]) | ((a[:, 0] == c[:, 0]) & (a[:, 1] > c[:, 1]))
    ends = np.where(swap[:, None], np.hstack([c, a]), np.hstack([a, c]))
    b = np.flatnonzero(border)
    _, inverse, counts = np.unique(ends[b], axis=0, return_inverse=True, return_counts=True)
    out[b[counts[inverse.reshape(-1)] > 1]] = True
    return out


def _merge_coincident(
    src: str, vertices: np.ndarray, edges: np.ndarray, columns: dict[str, np.ndarray]
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Merge vertices that coincide (to 1e-9 of the extent) before any triangulation sees them.

    Coincident vertices are legitimate only along a slit: a cut split into two border edges (as in our own folded
    meshes, and as the FOLD spec lets a ``C`` edge be stored). Such border pairs become one ``C`` edge. Anything
    else (an edge shrinking to a point, two creases on one segment, no border left, as in a flat-folded state)
    raises PatternError naming the vertices: triangle libraries crash or loop on such input.
    """
    n = len(vertices)
    if n < 2:
        return vertices, edges, columns
    size = float(np.ptp(vertices, axis=0).max()) or 1.0
    keys = np.round(vertices / (1e-9 * size)).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    if len(first) == n:
        return vertices, edges, columns
    dup = int(np.flatnonzero(first[inverse] != np.arange(n))[0])
    twin = int(first[inverse[dup]])
    where = f"vertices {twin} and {dup} coincide at ({vertices[dup, 0]:.6g}, {vertices[dup, 1]:.6g})"
    hint = "a crease pattern needs distinct vertices; is this a folded state? Export its crease pattern instead"
    assign = columns["assignments"]
    used = np.zeros(n, dtype=bool)
    used[first] = True
    new_index = (np.cumsum(used) - 1)[first[inverse]]  # every vertex → its merged vertex, original order kept
    merged = np.sort(new_index[edges], axis=1)
    point = merged[:, 0] == merged[:, 1]
    if point.any():
        k = int(np.flatnonzero(point)[0])
        raise PatternError(f"{src}: {where}; edge {k} {edges[k].tolist()} shrinks to a point ({hint})")
    _, first_e, inv_e, counts = np.unique(merged, axis=0, return_index=True, return_inverse=True, return_counts=True)
    inv_e = inv_e.reshape(-1)
    repeated = counts[inv_e] > 1
    slit = np.isin(assign, ("B", "C"))
    if np.any(repeated & ~slit):
        k = int(np.flatnonzero(repeated & ~slit)[0])
        raise PatternError(
            f"{src}: {where}; edge {k} ({assign[k]}) then lies on another edge, which only two border edges of a "
            f"slit may do ({hint})"
        )
    keep = np.zeros(len(edges), dtype=bool)
    keep[first_e] = True
    out = {name: np.asarray(col)[keep].copy() for name, col in columns.items()}
    out["assignments"][repeated[keep]] = "C"
    if not np.any(out["assignments"] == "B"):
        raise PatternError(f"{src}: {where}; every border edge then lies on another, so no border is left ({hint})")
    return vertices[used], merged[keep], out


def _drop_unused_vertices(vertices: np.ndarray, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    used = np.zeros(len(vertices), dtype=bool)
    used[edges.reshape(-1)] = True
    if used.all():
        return vertices, edges
    return vertices[used], (np.cumsum(used) - 1)[edges]


def _target_angles(doc: FoldDocument) -> np.ndarray:
    """Target fold angles as our models keep them: ``nan`` for "none given" (``curved_fold:angle_unset``) and
    for borders, cuts and undriven hinges written as the spec's 0."""
    angles = doc.fold_angles.copy()
    angles[np.isin(doc.assignments, ("B", "C", "U", "J")) & (angles == 0)] = np.nan
    unset = doc.data.get(PREFIX + "angle_unset")
    if isinstance(unset, list) and len(unset) == len(angles):
        angles[np.array(unset, dtype=bool)] = np.nan
    return angles


def fold_to_pattern(doc: FoldDocument, source: str | None = None) -> CreasePattern:
    """The flat crease pattern of a FOLD document (``source`` names it in ``sources`` and messages).

    ``curved_fold:`` fields written by :func:`write_pattern_fold` restore the polyline indices, from-curve flags and
    source names exactly; plain FOLD files get one polyline per edge named ``"<file> edge i"`` (grouped into
    strokes for folding: :func:`another_tools_segments`). Edges that are not
    part of the drawn pattern are dropped: ``J`` (join) edges and, in our folded files, the triangulation diagonals
    (``curved_fold:edge_polyline`` −1). Coincident vertices are merged along slits or refused
    (:func:`_merge_coincident`), so the triangulation never sees them.
    """
    src = source or doc.source_name
    if doc.vertices is None:
        raise PatternError(
            f"{src}: a folded (3D) FOLD file without a flat crease pattern (a 2D key frame, or "
            f"{PREFIX}flat_coords) has no crease pattern to read; export the crease pattern (2D) instead"
        )
    data = doc.data
    m = len(doc.edges)
    if PREFIX + "edge_polyline" in data:
        poly = np.array(data[PREFIX + "edge_polyline"], dtype=np.int64).reshape(-1)
        sources = [str(s) for s in data.get(PREFIX + "sources", [])]
        drawn = poly >= 0
        if len(poly) and sources and poly.max() >= len(sources):
            bad = int(np.flatnonzero(poly >= len(sources))[0])
            raise PatternError(
                f"{src}: {PREFIX}edge_polyline[{bad}] = {poly[bad]} out of range ({len(sources)} sources)"
            )
        if not sources:
            sources = [f"{src} polyline {k}" for k in range(int(poly.max()) + 1 if drawn.any() else 0)]
    else:
        poly = np.arange(m)
        drawn = np.ones(m, dtype=bool)
        sources = [f"{src} edge {k}" for k in range(m)]
    keep = drawn & (doc.assignments != "J")
    curve = np.array(data.get(PREFIX + "edge_from_curve", [False] * m), dtype=bool).reshape(-1)
    columns = {
        "assignments": doc.assignments[keep],
        "fold_angles": _target_angles(doc)[keep],
        "edge_polyline": poly[keep],
        "edge_from_curve": curve[keep],
    }
    columns["assignments"][cut_mask(doc.vertices, doc.edges, doc.assignments, doc.faces)[keep]] = "C"
    vertices, edges = doc.vertices, doc.edges[keep]
    if not keep.all():
        vertices, edges = _drop_unused_vertices(vertices, edges)
    vertices, edges, columns = _merge_coincident(src, vertices, edges, columns)
    pattern = CreasePattern(
        vertices=vertices,
        edges=edges,
        sources=sources,
        warnings=list(doc.warnings) + [str(w) for w in data.get(PREFIX + "warnings", [])],
        interval=_interval(doc, src),
        **columns,
    )
    pattern.validate()
    return pattern


def _interval(doc: FoldDocument, source: str) -> float:
    """``curved_fold:interval`` in mm (the interval our pattern was discretised at, in the file's unit; the
    triangulation splits long straight creases beside needles at it), or nan (another tool's file)."""
    value = doc.data.get(PREFIX + "interval")
    if value is None:
        return math.nan
    if isinstance(value, bool) or not isinstance(value, int | float) or not (value > 0 and math.isfinite(value)):
        raise PatternError(f"{source}: {PREFIX}interval must be a positive number, got {value!r}")
    return float(value) * UNIT_MM.get(doc.unit, 1.0)


def is_our_pattern(doc: FoldDocument) -> bool:
    """Whether ``doc`` is a pattern we wrote (its segments carry their source strokes, ``curved_fold:edge_polyline``):
    read back as written, where another tool's file is thinned and split (:func:`pattern_for_folding`)."""
    return PREFIX + "edge_polyline" in doc.data


def read_fold_pattern(
    path: str | os.PathLike[str], *, interval: float | None = None, tolerance: float | None = None
) -> CreasePattern:
    """The crease pattern a fold of the FOLD file ``path`` starts from (:func:`pattern_for_folding`)."""
    return pattern_for_folding(read_fold(path), interval=interval, tolerance=tolerance)


def pattern_for_folding(
    doc: FoldDocument, *, interval: float | None = None, tolerance: float | None = None
) -> CreasePattern:
    """The crease pattern a fold of ``doc`` starts from, the same through every door (command line, Blender
    import): :func:`fold_to_pattern` and, for another tool's file (no ``curved_fold:`` fields; ours keep the
    pieces they were discretised with and their curve flags), :func:`another_tools_segments` sampled as a drawing
    is at ``interval`` and ``tolerance`` (mm; ``None``: the paper's, scaled to the sheet; the interval is also the
    one long straight creases are split at beside needles; :func:`..pattern.discretize.segments_at_interval`). Our
    own files ignore them: they read back as written."""
    if is_our_pattern(doc):
        return fold_to_pattern(doc)
    return segments_at_interval(another_tools_segments(doc), interval, tolerance)


def another_tools_segments(doc: FoldDocument) -> CreasePattern:
    """Another tool's FOLD file as the straight segments it draws, before any sampling: its sliver facets left out
    (:func:`_without_sliver_facets`), its creases without a fold angle folding flat (:func:`_flat_foldable_angles`)
    and its edges that cross away from a vertex split there (:func:`..pattern.discretize.with_crossings_split`),
    its segments grouped into the strokes they draw (:func:`..pattern.polylines.drawn_strokes`: a crease is judged
    and named as one, as an SVG's path is).
    What depends on the interval is done by :func:`..pattern.discretize.segments_at_interval`, at fold time in
    Blender (the import keeps these segments), so the Fold panel's Interval applies as ``--interval`` does."""
    return drawn_strokes(with_crossings_split(fold_to_pattern(_flat_foldable_angles(_without_sliver_facets(doc)))))


def _flat_foldable_angles(doc: FoldDocument) -> FoldDocument:
    """``doc`` with its mountains and valleys that have no fold angle (no ``edges_foldAngle``, or a null in it)
    folding to −180° and 180°, with a warning: a crease pattern from Rabbit Ear, ORIPA or the FOLD spec's own
    examples means flat-foldable creases, and Origami Simulator's importer offers the same (its issue #33 asks for
    it by default). They stayed flat before, silently (a helper's waterbomb, Huffman arcs and concentric rings:
    "converged, 0 iterations")."""
    missing = np.isin(doc.assignments, ("M", "V")) & ~np.isfinite(doc.fold_angles)
    if not missing.any():
        return doc
    angles = doc.fold_angles.copy()
    angles[missing] = np.where(doc.assignments[missing] == "M", -180.0, 180.0)
    where = "null in edges_foldAngle" if "edges_foldAngle" in doc.data else "no edges_foldAngle in the file"
    said = (
        f"{doc.source_name}: {int(missing.sum())} mountain/valley edge(s) without a fold angle ({where}) fold to "
        "−180°/180°, as a flat-foldable crease pattern means them; a fold percent scales them (50 % folds them to 90°)"
    )
    return replace(doc, fold_angles=angles, warnings=[*doc.warnings, said])


SLIVER_FACET_DEG = 1.0
"""A file whose faces are all triangles, with a corner under this (degrees) beside a facet (F) edge, is taken as an
export's triangulation: its facet edges are dropped."""


def _triangles_at(edges: np.ndarray, which: np.ndarray) -> np.ndarray:
    """The triangles ``(k, 3)`` that the edges close around the edges ``which`` (3-cycles of the edge graph
    through one of them): a file's triangulation when it gives no faces."""
    around: dict[int, set[int]] = {}
    for i, j in edges.tolist():
        around.setdefault(i, set()).add(j)
        around.setdefault(j, set()).add(i)
    found = {tuple(sorted((i, j, k))) for i, j in edges[which].tolist() for k in around[i] & around[j]}
    return np.array(sorted(found), dtype=np.int64).reshape(-1, 3)


def _without_sliver_facets(doc: FoldDocument) -> FoldDocument:
    """``doc`` without its flat facet edges (F, angle 0) when they triangulate its faces badly: every face a
    triangle, and one with a corner under :data:`SLIVER_FACET_DEG` beside a facet edge. That is an export's
    triangulation, not a design: Origami Simulator saves its earcut triangles of the faces between long curved
    polylines as F edges (corners down to 0.002°), which no solver folds (500 iterations, residual 2e5; dropping
    only the edges beside the slivers left the rest of the earcut fan, still 500 iterations). The sheet is then
    meshed along its rulings, as a drawing is, and a warning says so. A file without faces is judged by the
    triangles its edges close around its facets (such an export without ``faces_vertices`` stalled the same way).
    Facets of polygon faces, or of a triangulation without slivers, are kept: they are the designer's."""
    facet = (doc.assignments == "F") & ~(np.abs(np.nan_to_num(doc.fold_angles)) > 0)
    if any(len(f) != 3 for f in doc.faces) or not facet.any() or doc.vertices is None:
        return doc
    tri = np.asarray(doc.faces, dtype=np.int64).reshape(-1, 3) if doc.faces else _triangles_at(doc.edges, facet)
    if not len(tri):
        return doc
    thin = tri[corner_angles(np.asarray(doc.vertices)[:, :2], tri).min(axis=1) < SLIVER_FACET_DEG]
    n = max(len(doc.vertices), 1)
    sides = polygon_sides(thin)
    pairs = np.sort(doc.edges, axis=1)
    if not np.isin(pairs[facet, 0] * n + pairs[facet, 1], sides[:, 0] * n + sides[:, 1]).any():
        return doc
    assignments = doc.assignments.copy()
    assignments[facet] = "J"  # left out of the pattern as join edges are
    said = (
        f"{doc.source_name}: its {int(facet.sum())} facet (F) edge(s) triangulate the faces with corners under "
        f"{SLIVER_FACET_DEG:g}° (an export's triangulation, as Origami Simulator saves it): they are left out and "
        "the sheet is meshed along its rulings"
    )
    return replace(doc, assignments=assignments, warnings=[*doc.warnings, said])


def fold_to_mesh(doc: FoldDocument, source: str | None = None) -> FoldMesh:
    """The triangle mesh of a FOLD file whose faces are triangles (our folded files): flat positions, triangles,
    edges, assignments, target angles and our ``curved_fold:`` fields as written by :func:`write_folded_fold`, so
    a folded file reads back to the mesh it was written from. Raises PatternError otherwise."""
    src = source or doc.source_name
    if doc.vertices is None:
        raise PatternError(f"{src}: no flat crease pattern in the file, so no mesh to rebuild")
    tris = doc.faces
    if not tris or any(len(f) != 3 for f in tris):
        raise PatternError(f"{src}: faces_vertices are not all triangles; fold the file to get a mesh")
    data, m = doc.data, len(doc.edges)

    def column(name: str, default: Any, dtype: Any) -> np.ndarray:
        value = data.get(PREFIX + name, default)
        arr = np.asarray(value, dtype=dtype).reshape(-1)
        if len(arr) != len(default):
            raise PatternError(f"{src}: {PREFIX}{name} has {len(arr)} entries, expected {len(default)}")
        return arr

    angles = _target_angles(doc)
    angles[np.isin(doc.assignments, ("B", "U"))] = np.nan
    angles[(doc.assignments == "F") & ~np.isfinite(angles)] = 0.0
    faces = data.get(PREFIX + "pattern_faces", [])
    return FoldMesh(
        vertices=doc.vertices,
        triangles=tris,
        edges=np.sort(doc.edges, axis=1),
        assignments=np.where(doc.assignments == "J", "F", doc.assignments),
        fold_angles=angles,
        edge_from_curve=column("edge_from_curve", [False] * m, bool),
        edge_polyline=column("edge_polyline", list(range(m)), np.int64),
        triangle_face=column("triangle_face", [0] * len(tris), np.int64),
        faces=[np.asarray(f, dtype=np.int64) for f in faces] if isinstance(faces, list) else [],
        mesh_type=str(data.get(PREFIX + "mesh_type", "ruling")),
        sources=[str(s) for s in data.get(PREFIX + "sources", [])],
        interval=_interval(doc, src),
    )


def _angles_json(a: np.ndarray, assignments: np.ndarray | None = None) -> list[float]:
    """Fold angles as the spec's numbers: an angle not given (``nan``) is 0 (flat, border, unassigned), or ±180
    for a mountain/valley (Origami Simulator's reading of a crease without an angle)."""
    a = np.asarray(a, dtype=float).copy()
    missing = ~np.isfinite(a)
    a[missing] = 0.0
    if assignments is not None:
        a[missing & (assignments == "M")] = -180.0
        a[missing & (assignments == "V")] = 180.0
    return a.tolist()


def _header(frame_class: str, dims: str, unit: str, animation: bool = False) -> dict[str, Any]:
    return {
        "file_spec": 1.1,
        "file_creator": CREATOR,
        "file_classes": ["singleModel", "animation"] if animation else ["singleModel"],
        "frame_classes": [frame_class],
        "frame_attributes": [dims],
        "frame_unit": unit,
    }


def pattern_to_fold(pattern: CreasePattern) -> dict[str, Any]:
    """The FOLD object :func:`write_pattern_fold` writes. Every fold angle is a number; creases without one are
    written as ±180 and listed in ``curved_fold:angle_unset`` so that reading back restores "none given"."""
    pattern.validate()
    data = _header("creasePattern", "2D", "mm")
    if np.any(pattern.assignments == "C"):
        data["frame_attributes"].append("cuts")
        data["file_spec"] = 1.2  # "C" edges were added in FOLD 1.2
    unset = np.isin(pattern.assignments, ("M", "V")) & ~np.isfinite(pattern.fold_angles)
    data.update(
        {
            "vertices_coords": pattern.vertices.tolist(),
            "edges_vertices": pattern.edges.tolist(),
            "edges_assignment": pattern.assignments.tolist(),
            "edges_foldAngle": _angles_json(pattern.fold_angles, pattern.assignments),
            PREFIX + "edge_polyline": pattern.edge_polyline.tolist(),
            PREFIX + "edge_from_curve": pattern.edge_from_curve.tolist(),
            PREFIX + "sources": list(pattern.sources),
            PREFIX + "warnings": list(pattern.warnings),
        }
    )
    if unset.any():
        data[PREFIX + "angle_unset"] = unset.tolist()
    if math.isfinite(pattern.interval):
        data[PREFIX + "interval"] = pattern.interval
    return data


def write_pattern_fold(path: str | os.PathLike[str], pattern: CreasePattern) -> Path:
    """Write a discretised crease pattern as a 2D FOLD file in mm, atomically; returns the path written."""
    return atomic_write_text(path, json.dumps(pattern_to_fold(pattern), indent=1, allow_nan=False) + "\n")


def folded_to_fold(
    mesh: FoldMesh,
    frames: list[np.ndarray],
    fold_angles: list[np.ndarray] | None = None,
    unit: str = "mm",
    extra: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The FOLD object :func:`write_folded_fold` writes (checks shapes, raising PatternError).

    The spec's conventions, so that Origami Simulator and FOLD viewers open it flat and fold it: the key frame is
    the crease pattern (2D, ``creasePattern``, the mesh's triangles as faces, target fold angles, diagonals ``F``
    at 0); every folded state is a ``file_frames`` entry (``foldedForm``, 3D, inheriting the key frame, its own
    simulated ``edges_foldAngle``, limited to the spec's [−180°, 180°]); several frames make the file an
    ``animation``.
    """
    _check_folded(mesh, frames, fold_angles, unit)
    file_frames = [
        _folded_frame(mesh, k, f, None if fold_angles is None else fold_angles[k], unit) for k, f in enumerate(frames)
    ]
    data = _folded_key_frame(mesh, len(frames), unit)
    data["file_frames"] = file_frames
    if extra:
        data.update(extra)
    return data


def _check_folded(mesh: FoldMesh, frames: list[np.ndarray], fold_angles: list[np.ndarray] | None, unit: str) -> None:
    if not len(frames):
        raise PatternError("folded FOLD export: no frame to write")
    if unit not in UNIT_MM:
        raise PatternError(f"folded FOLD export: unknown unit {unit!r} (expected one of {', '.join(UNIT_MM)})")
    if fold_angles is not None and len(fold_angles) != len(frames):
        raise PatternError(f"folded FOLD export: {len(fold_angles)} fold-angle arrays for {len(frames)} frames")


def _folded_key_frame(mesh: FoldMesh, n_frames: int, unit: str) -> dict[str, Any]:
    """The key frame of a folded FOLD file (the crease pattern), without ``file_frames``."""
    scale = 1.0 / UNIT_MM[unit]
    data = _header("creasePattern", "2D", unit, animation=n_frames > 1)
    data.update(
        {
            "vertices_coords": (mesh.vertices * scale).tolist(),
            "edges_vertices": mesh.edges.tolist(),
            "edges_assignment": mesh.assignments.tolist(),
            "edges_foldAngle": _angles_json(mesh.fold_angles, mesh.assignments),
            "faces_vertices": mesh.triangles.tolist(),
            PREFIX + "edge_polyline": mesh.edge_polyline.tolist(),
            PREFIX + "edge_from_curve": mesh.edge_from_curve.tolist(),
            PREFIX + "sources": list(mesh.sources),
            PREFIX + "mesh_type": mesh.mesh_type,
            PREFIX + "triangle_face": mesh.triangle_face.tolist(),
            PREFIX + "pattern_faces": [np.asarray(f).tolist() for f in mesh.faces],
        }
    )
    if math.isfinite(mesh.interval):  # read back, its long straight creases are split as they were
        data[PREFIX + "interval"] = mesh.interval * scale
    return data


def _folded_frame(mesh: FoldMesh, k: int, positions: np.ndarray, angles: np.ndarray | None, unit: str) -> dict:
    """The ``file_frames`` entry of frame ``k`` (positions in mm, simulated angles in degrees or None)."""
    n, e = mesh.n_vertices, len(mesh.edges)
    f = np.asarray(positions, dtype=float)
    if f.shape != (n, 3):
        raise PatternError(f"folded FOLD export: frame {k} has shape {f.shape}, expected ({n}, 3)")
    if not np.isfinite(f).all():
        raise PatternError(f"folded FOLD export: frame {k} has non-finite positions")
    fr: dict[str, Any] = {
        "frame_classes": ["foldedForm"],
        "frame_attributes": ["3D"],
        "frame_parent": 0,
        "frame_inherit": True,
        "vertices_coords": (f * (1.0 / UNIT_MM[unit])).tolist(),
    }
    if angles is not None:
        a = np.asarray(angles, dtype=float).reshape(-1)
        if len(a) != e:
            raise PatternError(
                f"folded FOLD export: fold angles of frame {k} have {len(a)} entries, mesh has {e} edges"
            )
        # the solver's angles are unwrapped: a crease driven past flat (no contact, as in Origami Simulator) reads
        # e.g. 192°; the spec's range is [−180°, 180°] with the sign of the assignment, so it is written as folded
        # flat (the frame's vertices_coords keep the exact geometry)
        fr["edges_foldAngle"] = _angles_json(np.clip(a, -180.0, 180.0))
    return fr


def folded_fold_text_steps(
    mesh: FoldMesh,
    frames: list[np.ndarray],
    fold_angles: list[np.ndarray] | None = None,
    unit: str = "mm",
    extra: dict[str, Any] | None = None,
) -> Generator[int, None, str]:
    """The text of :func:`write_folded_fold`'s file in units of work: the key frame, then one frame per ``next``
    (yields the index of the frame it encodes next); returns the whole text, byte for byte ``json.dumps`` of
    :func:`folded_to_fold` plus a newline. Encoding 60 frames of a 3,000-face pattern in one ``json.dumps`` took
    ~220 ms; an export job runs these units in slices (``scene.export``)."""
    _check_folded(mesh, frames, fold_angles, unit)
    data = _folded_key_frame(mesh, len(frames), unit)
    data["file_frames"] = None  # its place among the keys: encoded frame by frame below
    if extra:
        data.update(extra)

    def member(key: str, value: Any) -> str:  # what json.dumps writes for one entry of a dict (", ", ": ")
        return json.dumps(key) + ": " + json.dumps(value, allow_nan=False)

    keys = list(data)
    split = keys.index("file_frames")
    head = [member(k, data[k]) for k in keys[:split]]
    encoded = []
    for k, f in enumerate(frames):
        yield k
        angles = None if fold_angles is None else fold_angles[k]
        encoded.append(json.dumps(_folded_frame(mesh, k, f, angles, unit), allow_nan=False))
    tail = [member(k, data[k]) for k in keys[split + 1 :]]
    body = [*head, json.dumps("file_frames") + ": [" + ", ".join(encoded) + "]", *tail]
    return "{" + ", ".join(body) + "}\n"


def write_folded_fold(
    path: str | os.PathLike[str],
    mesh: FoldMesh,
    frames: list[np.ndarray],
    fold_angles: list[np.ndarray] | None = None,
    unit: str = "mm",
    extra: dict[str, Any] | None = None,
) -> Path:
    """Write a folded mesh atomically (:func:`folded_to_fold`): the crease pattern as the key frame, ``frames``
    (mm) as ``file_frames``, ``fold_angles`` (degrees, one array per frame, simulated) as each frame's
    ``edges_foldAngle``. ``extra`` entries are added at the top level (prefix your keys)."""
    return atomic_write_text(path, run_to_end(folded_fold_text_steps(mesh, frames, fold_angles, unit, extra)))
