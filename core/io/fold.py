"""FOLD files (https://github.com/edemaine/fold, spec 1.1): read crease patterns and folded states, write both.

Reading (:func:`read_fold`, :func:`fold_to_pattern`): ``vertices_coords`` (2D, or 3D with z ≈ 0 which counts as
flat; a folded 3D file is read as frames), ``edges_vertices``, ``edges_assignment`` (lowercase accepted),
``edges_foldAngle`` in degrees (the v1.0 spelling ``edges_foldAngles`` too), ``faces_vertices``, ``file_frames``
(with ``frame_parent``/``frame_inherit``) and ``frame_unit``. Every problem raises :class:`~.pattern.PatternError`
naming the array and index.

Writing is atomic (:mod:`.files`). :func:`write_pattern_fold` stores a discretised pattern (2D, ``creasePattern``,
mm) with our own ``curved_fold:`` fields (source polyline, from-curve flag, sources), so SVG → pattern → FOLD →
pattern is lossless (floats are written with ``repr`` precision). :func:`write_folded_fold` stores a folded mesh:
triangles as faces, 3D positions per frame, flat positions and simulated fold angles as ``curved_fold:`` fields.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..mesh.fold_mesh import FoldMesh
from ..pattern.model import ASSIGNMENTS, CreasePattern, PatternError
from .atomic import atomic_write_text

UNIT_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "pt": 25.4 / 72.0, "um": 1e-3, "nm": 1e-6, "unit": 1.0}
"""Millimetres per FOLD ``frame_unit``; ``unit`` (unitless, the FOLD default) is taken as millimetres."""

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


def parse_fold(text: str, source_name: str = "<fold>") -> FoldDocument:
    """Check and convert FOLD JSON text (see :class:`FoldDocument`)."""
    src = source_name
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise _fail(src, f"malformed JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    if not isinstance(data, dict):
        raise _fail(src, "a FOLD file must be a JSON object")
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
        if s not in ASSIGNMENTS:
            raise _fail(src, f"edges_assignment[{i}] = {a!r} is not one of {', '.join(ASSIGNMENTS)}")
        assignments.append(s)
    assign = np.array(assignments, dtype="<U1")
    if "edges_foldAngle" in data:
        angles = _angles(data["edges_foldAngle"], "edges_foldAngle", src)
    else:
        angles = np.where(assign == "F", 0.0, np.nan)
    faces = []
    if "faces_vertices" in data:
        faces = _index_array(data["faces_vertices"], "faces_vertices", src, None, n, "vertices")
    extent = float(np.max(np.ptp(coords, axis=0))) if n else 0.0
    flat_key = PREFIX + "flat_coords"
    frames: list[np.ndarray] = []
    frame_angles: list[np.ndarray | None] = []
    key_is_flat = coords.shape[1] == 2 or np.all(np.abs(coords[:, 2]) <= 1e-9 * max(extent, 1.0))
    if flat_key in data:
        flat = _coords(data[flat_key], flat_key, src, scale)
        if len(flat) != n:
            raise _fail(src, f"{flat_key} has {len(flat)} entries but vertices_coords has {n}")
        flat = flat[:, :2]
    elif key_is_flat:
        flat = coords[:, :2].copy()
    else:
        flat = None
    fa_key = PREFIX + "fold_angles"

    def frame_angles_of(fr: dict, where: str) -> np.ndarray | None:
        if fa_key not in fr:
            return None
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
        frames.append(fc)
        frame_angles.append(frame_angles_of(merged, where))
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


def fold_to_pattern(doc: FoldDocument, source: str | None = None) -> CreasePattern:
    """The flat crease pattern of a FOLD document (``source`` names it in ``sources`` and messages).

    ``curved_fold:`` fields written by :func:`write_pattern_fold` restore the polyline indices, from-curve flags and
    source names exactly; plain FOLD files get one polyline per edge named ``"<file> edge i"``.
    """
    src = source or doc.source_name
    if doc.vertices is None:
        raise PatternError(
            f"{src}: a folded (3D) FOLD file without {PREFIX}flat_coords has no crease pattern to read; "
            "export the crease pattern (2D) instead"
        )
    data = doc.data
    m = len(doc.edges)
    if PREFIX + "edge_polyline" in data:
        poly = np.array(data[PREFIX + "edge_polyline"], dtype=np.int64)
        sources = [str(s) for s in data.get(PREFIX + "sources", [])]
        if len(poly) and sources and (poly.min() < 0 or poly.max() >= len(sources)):
            bad = int(np.flatnonzero((poly < 0) | (poly >= len(sources)))[0])
            raise PatternError(
                f"{src}: {PREFIX}edge_polyline[{bad}] = {poly[bad]} out of range ({len(sources)} sources)"
            )
        if not sources:
            sources = [f"{src} polyline {k}" for k in range(int(poly.max()) + 1 if len(poly) else 0)]
    else:
        poly = np.arange(m)
        sources = [f"{src} edge {k}" for k in range(m)]
    curve = np.array(data.get(PREFIX + "edge_from_curve", [False] * m), dtype=bool)
    pattern = CreasePattern(
        vertices=doc.vertices,
        edges=doc.edges,
        assignments=doc.assignments,
        fold_angles=doc.fold_angles,
        edge_polyline=poly,
        edge_from_curve=curve,
        sources=sources,
        warnings=list(doc.warnings) + [str(w) for w in data.get(PREFIX + "warnings", [])],
    )
    pattern.validate()
    return pattern


def _angles_json(a: np.ndarray) -> list[float | None]:
    return [None if not math.isfinite(x) else float(x) for x in np.asarray(a, dtype=float).tolist()]


def _header(frame_class: str, dims: str, unit: str) -> dict[str, Any]:
    return {
        "file_spec": 1.1,
        "file_creator": CREATOR,
        "file_classes": ["singleModel"],
        "frame_classes": [frame_class],
        "frame_attributes": [dims],
        "frame_unit": unit,
    }


def pattern_to_fold(pattern: CreasePattern) -> dict[str, Any]:
    """The FOLD object :func:`write_pattern_fold` writes."""
    pattern.validate()
    data = _header("creasePattern", "2D", "mm")
    data.update(
        {
            "vertices_coords": pattern.vertices.tolist(),
            "edges_vertices": pattern.edges.tolist(),
            "edges_assignment": pattern.assignments.tolist(),
            "edges_foldAngle": _angles_json(pattern.fold_angles),
            PREFIX + "edge_polyline": pattern.edge_polyline.tolist(),
            PREFIX + "edge_from_curve": pattern.edge_from_curve.tolist(),
            PREFIX + "sources": list(pattern.sources),
            PREFIX + "warnings": list(pattern.warnings),
        }
    )
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
    """The FOLD object :func:`write_folded_fold` writes (checks shapes, raising PatternError)."""
    n, e = mesh.n_vertices, len(mesh.edges)
    if not frames:
        raise PatternError("folded FOLD export: no frame to write")
    if unit not in UNIT_MM:
        raise PatternError(f"folded FOLD export: unknown unit {unit!r} (expected one of {', '.join(UNIT_MM)})")
    scale = 1.0 / UNIT_MM[unit]
    pos = []
    for k, f in enumerate(frames):
        f = np.asarray(f, dtype=float)
        if f.shape != (n, 3):
            raise PatternError(f"folded FOLD export: frame {k} has shape {f.shape}, expected ({n}, 3)")
        if not np.isfinite(f).all():
            raise PatternError(f"folded FOLD export: frame {k} has non-finite positions")
        pos.append((f * scale).tolist())
    angles: list[list[float | None]] | None = None
    if fold_angles is not None:
        if len(fold_angles) != len(frames):
            raise PatternError(f"folded FOLD export: {len(fold_angles)} fold-angle arrays for {len(frames)} frames")
        angles = []
        for k, a in enumerate(fold_angles):
            a = np.asarray(a, dtype=float).reshape(-1)
            if len(a) != e:
                raise PatternError(
                    f"folded FOLD export: fold angles of frame {k} have {len(a)} entries, mesh has {e} edges"
                )
            angles.append(_angles_json(a))
    data = _header("foldedForm", "3D", unit)
    data.update(
        {
            "vertices_coords": pos[0],
            "edges_vertices": mesh.edges.tolist(),
            "edges_assignment": mesh.assignments.tolist(),
            "edges_foldAngle": _angles_json(mesh.fold_angles),
            "faces_vertices": mesh.triangles.tolist(),
            PREFIX + "flat_coords": (mesh.vertices * scale).tolist(),
            PREFIX + "edge_polyline": mesh.edge_polyline.tolist(),
            PREFIX + "edge_from_curve": mesh.edge_from_curve.tolist(),
            PREFIX + "sources": list(mesh.sources),
            PREFIX + "mesh_type": mesh.mesh_type,
        }
    )
    if angles is not None:
        data[PREFIX + "fold_angles"] = angles[0]
    if len(pos) > 1:
        data["file_frames"] = []
        for k in range(1, len(pos)):
            fr: dict[str, Any] = {
                "frame_classes": ["foldedForm"],
                "frame_attributes": ["3D"],
                "frame_parent": 0,
                "frame_inherit": True,
                "vertices_coords": pos[k],
            }
            if angles is not None:
                fr[PREFIX + "fold_angles"] = angles[k]
            data["file_frames"].append(fr)
    if extra:
        data.update(extra)
    return data


def write_folded_fold(
    path: str | os.PathLike[str],
    mesh: FoldMesh,
    frames: list[np.ndarray],
    fold_angles: list[np.ndarray] | None = None,
    unit: str = "mm",
    extra: dict[str, Any] | None = None,
) -> Path:
    """Write a folded mesh atomically: triangles as faces, ``frames[0]`` as ``vertices_coords`` (3D), the other
    frames in ``file_frames``, flat positions in ``curved_fold:flat_coords``, simulated angles (one array per frame,
    degrees) in ``curved_fold:fold_angles``. ``extra`` entries are added at the top level (prefix your keys)."""
    data = folded_to_fold(mesh, frames, fold_angles, unit, extra)
    return atomic_write_text(path, json.dumps(data, allow_nan=False) + "\n")
