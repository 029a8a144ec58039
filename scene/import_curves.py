"""Import a crease pattern file (SVG, FOLD) as editable Bézier curve objects with their crease roles set.

SVG strokes keep their exact geometry (lines, cubics, arcs) from ``core.svg.read_svg``; a FOLD file holds straight
segments only, so its edges are chained into polylines (one curve per chain of one assignment and angle, through
vertices where exactly two such edges meet). The curve objects are made by ``scene.curves.objects_from_curves``
(the inverse of ``curves_from_objects``), inside a new collection named after the file. Nothing is written to the
scene until the whole file has been read and converted; on failure whatever was created is removed.
"""

from __future__ import annotations

from pathlib import Path

import bpy
import numpy as np

from ..core.pattern import CreaseCurve, CreasePattern, CurveSegment, PatternError

SUFFIXES = (".svg", ".fold")


def curves_from_pattern(pattern: CreasePattern) -> list[CreaseCurve]:
    """Chain the straight segments of a discretised pattern into polyline :class:`CreaseCurve` s.

    Segments are grouped by (assignment, fold angle, source polyline) and chained through vertices of degree 2
    within the group, so a FOLD file's discretised curve comes back as one editable curve, not hundreds.
    """
    from .mesh_object import chain_edges

    angles = np.round(np.nan_to_num(pattern.fold_angles, nan=np.inf), 9)
    keys = {}
    rows = zip(pattern.assignments.tolist(), angles.tolist(), pattern.edge_polyline.tolist(), strict=True)
    for i, key in enumerate(rows):
        keys.setdefault(key, []).append(i)
    curves: list[CreaseCurve] = []
    for (assignment, angle, poly), idx in keys.items():
        for chain in chain_edges(pattern.edges[idx]):
            pts = pattern.vertices[chain]
            closed = len(chain) > 2 and chain[0] == chain[-1]
            segs = [CurveSegment("line", np.array([pts[k], pts[k + 1]])) for k in range(len(pts) - 1)]
            src = pattern.sources[poly] if 0 <= poly < len(pattern.sources) else f"FOLD edges {idx[:3]}..."
            curves.append(
                CreaseCurve(
                    segments=segs,
                    assignment=assignment,
                    fold_angle=None if not np.isfinite(angle) else float(angle),
                    closed=bool(closed),
                    source=src,
                )
            )
    return curves


def read_curves(path: str | Path) -> tuple[list[CreaseCurve], list[str]]:
    """Read ``path`` (.svg or .fold) into crease curves and warnings; raises :class:`PatternError` naming the file."""
    path = Path(path)
    suffix = path.suffix.lower()
    if not path.is_file():
        raise PatternError(f"{path}: no such file")
    if suffix == ".svg":
        from ..core import svg

        drawing = svg.read_svg(path)
        return list(drawing.curves), list(getattr(drawing, "warnings", []))
    if suffix == ".fold":
        from ..core import fold_format

        result = fold_format.read_fold(path)
        pattern = result if isinstance(result, CreasePattern) else getattr(result, "pattern", None)
        if pattern is None:
            raise PatternError(f"{path}: the FOLD reader returned no crease pattern")
        return curves_from_pattern(pattern), list(pattern.warnings)
    raise PatternError(f"{path}: cannot import '{suffix}' files; expected one of {', '.join(SUFFIXES)}")


def import_crease_pattern(
    path: str | Path,
    *,
    scene: bpy.types.Scene | None = None,
    collection: bpy.types.Collection | None = None,
) -> tuple[list[bpy.types.Object], list[str]]:
    """Import ``path`` as curve objects in a new collection (child of ``collection`` or the scene's); return
    ``(objects, warnings)``. The scene is unchanged if reading or conversion fails."""
    scene = scene or bpy.context.scene
    curves, warnings = read_curves(path)
    if not curves:
        raise PatternError(f"{path}: no crease lines found")
    from .mesh_object import mm_per_unit

    parent = collection or scene.collection
    coll = bpy.data.collections.new(Path(path).stem)
    before = set(bpy.data.objects), set(bpy.data.curves), set(bpy.data.materials)
    try:
        parent.children.link(coll)
        objects = _objects_from_curves(curves, coll, 1.0 / mm_per_unit(scene))
    except Exception:
        for ob in set(bpy.data.objects) - before[0]:
            bpy.data.objects.remove(ob)
        for cu in set(bpy.data.curves) - before[1]:
            bpy.data.curves.remove(cu)
        for mat in set(bpy.data.materials) - before[2]:
            bpy.data.materials.remove(mat)
        bpy.data.collections.remove(coll)
        raise
    return objects, warnings


def _objects_from_curves(curves, coll, unit_scale):
    """``scene.curves.objects_from_curves`` (BLENDER-INFRA's), or a minimal local version while it is missing."""
    try:
        from .curves import objects_from_curves
    except ImportError:
        objects_from_curves = None
    if objects_from_curves is not None:
        return objects_from_curves(curves, coll, unit_scale)
    return _fallback_objects_from_curves(curves, coll, unit_scale)


_ROLES = {"B": "BORDER", "M": "MOUNTAIN", "V": "VALLEY", "F": "FACET", "U": "UNDRIVEN", "C": "CUT"}


def _cubic(seg: CurveSegment) -> list[np.ndarray]:
    """Control points of ``seg`` as cubic Bézier pieces (arcs split into ≤ 90° pieces, 4/3·tan(θ/4) handles)."""
    if seg.kind == "cubic":
        return [seg.points]
    if seg.kind == "line":
        a, b = seg.points
        return [np.array([a, a + (b - a) / 3, a + 2 * (b - a) / 3, b])]
    cx, cy, rx, ry, phi, t0, dt = seg.arc
    k = max(1, int(np.ceil(abs(dt) / (np.pi / 2) - 1e-9)))
    out = []
    for i in range(k):
        a0, a1 = t0 + dt * i / k, t0 + dt * (i + 1) / k
        h = 4.0 / 3.0 * np.tan((a1 - a0) / 4.0)
        local = np.array(
            [
                [np.cos(a0), np.sin(a0)],
                [np.cos(a0) - h * np.sin(a0), np.sin(a0) + h * np.cos(a0)],
                [np.cos(a1) + h * np.sin(a1), np.sin(a1) - h * np.cos(a1)],
                [np.cos(a1), np.sin(a1)],
            ]
        ) * np.array([rx, ry])
        c, s = np.cos(phi), np.sin(phi)
        out.append(local @ np.array([[c, s], [-s, c]]) + np.array([cx, cy]))
    return out


def _fallback_objects_from_curves(curves, coll, unit_scale):
    objects = []
    for i, curve in enumerate(curves):
        pieces = [p for seg in curve.segments for p in _cubic(seg)]
        cu = bpy.data.curves.new(f"Crease.{i:03d}", type="CURVE")
        cu.dimensions = "2D"
        sp = cu.splines.new("BEZIER")
        closed = curve.closed and np.allclose(pieces[-1][3], pieces[0][0])
        knots = len(pieces) + (0 if closed else 1)
        sp.bezier_points.add(knots - 1)
        for j, bp in enumerate(sp.bezier_points):
            bp.handle_left_type = bp.handle_right_type = "FREE"
            prev = pieces[j - 1] if j > 0 or closed else None
            nxt = pieces[j] if j < len(pieces) else None
            co = nxt[0] if nxt is not None else prev[3]
            bp.co = (*(co * unit_scale), 0.0)
            bp.handle_right = (*((nxt[1] if nxt is not None else co) * unit_scale), 0.0)
            bp.handle_left = (*((prev[2] if prev is not None else co) * unit_scale), 0.0)
        sp.use_cyclic_u = bool(closed)
        ob = bpy.data.objects.new(cu.name, cu)
        coll.objects.link(ob)
        props = getattr(ob, "curved_fold", None)
        if props is not None:
            props.role = _ROLES.get(curve.assignment, "NONE")
            if curve.fold_angle is not None and hasattr(props, "fold_angle"):
                props.fold_angle = abs(curve.fold_angle)
        objects.append(ob)
    return objects
