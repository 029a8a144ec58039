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
    within the group, so a FOLD file's discretised curve comes back as one editable curve, not hundreds. A plain
    FOLD file (every edge its own polyline) is grouped by assignment and angle only.
    """
    from .mesh_object import chain_edges

    angles = np.round(np.nan_to_num(pattern.fold_angles, nan=np.inf), 9)
    poly_ids = pattern.edge_polyline
    if len(np.unique(poly_ids)) == len(poly_ids):  # plain FOLD: one "polyline" per edge carries no grouping
        poly_ids = np.full(len(poly_ids), -1)
    keys = {}
    rows = zip(pattern.assignments.tolist(), angles.tolist(), poly_ids.tolist(), strict=True)
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

        pattern = fold_format.fold_to_pattern(fold_format.read_fold(path))
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
    from .curves import objects_from_curves  # BLENDER-INFRA's inverse of curves_from_objects

    return objects_from_curves(curves, coll, unit_scale)
