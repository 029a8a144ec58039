"""Crease curves drawn in Blender ↔ the engine's :class:`~..core.pattern.CreaseCurve` (paper §3.1: the input).

* :func:`curves_from_objects` reads Bézier and Poly splines of curve objects that have a crease role
  (``Object.curved_fold``, see :mod:`.properties`), in world space, as exact segments in millimetres.
* :func:`read_blend_file` does the same for every role-carrying curve object of a ``.blend`` file on disk (the
  ``.blend`` input of ``core.reader``), without changing the file open in Blender.
* :func:`objects_from_curves` is the inverse, used by the Import operator: one Bézier curve object per
  crease curve, role and angle set; arcs become cubic Béziers.

Units: the engine works in millimetres, Blender in Blender units (BU); 1 BU = 1000 mm × the scene's
``unit_settings.scale_length``. ``unit_scale`` everywhere in this module is **Blender units per millimetre**
(default ``1 / (1000 × scale_length)``), so ``BU = mm × unit_scale`` and ``mm = BU / unit_scale``.

A Bézier spline's segment i runs from ``co[i]`` through ``handle_right[i]`` and ``handle_left[i+1]`` to
``co[i+1]`` (a cubic), plus the closing segment ``n-1 → 0`` when the spline is cyclic — exactly the curve Blender
draws. A cubic whose handles lie on its chord, between its ends, is a straight line and becomes a ``"line"``
segment, so straight creases stay straight (the ruling-aware swaps treat them differently from curves).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path

import bpy
import numpy as np

from ..core.io.reader import register_blend_reader
from ..core.pattern.model import CreaseCurve, CurveSegment, PatternError
from .properties import ASSIGNMENT_ROLE, ROLE_ASSIGNMENT

PLANE_TOLERANCE = 1e-5
"""Allowed spread of z (relative to the pattern's size, at least 1 mm) for curves to count as one XY plane."""


def default_unit_scale(scene: bpy.types.Scene | None = None) -> float:
    """Blender units per millimetre in ``scene`` (the context scene by default): ``1 / (1000 × scale_length)``."""
    scene = scene or bpy.context.scene
    scale = float(scene.unit_settings.scale_length) if scene is not None else 1.0
    # scale_length is a float32 (0.001 reads back as 0.0010000000475): round to its 7 significant digits so a
    # typed-in 0.001 means exactly 1 BU = 1 mm.
    scale = float(f"{scale:.7g}")
    return 1.0 / (1000.0 * (scale if scale > 0.0 else 1.0))


def _role_and_angle(ob: bpy.types.Object) -> tuple[str, float]:
    props = getattr(ob, "curved_fold", None)
    if props is None:
        return "NONE", 180.0
    return props.role, float(props.fold_angle)


def _signed_angle(role: str, magnitude: float) -> float | None:
    if role == "VALLEY":
        return magnitude
    if role == "MOUNTAIN":
        return -magnitude
    if role == "FACET":
        return 0.0
    return None


def _segment(p: np.ndarray) -> CurveSegment | None:
    """A cubic from 4 control points (mm, 2D); a line if it is straight between its ends; None if a point."""
    chord = p[3] - p[0]
    length2 = float(chord @ chord)
    if length2 == 0.0:
        return None if np.allclose(p, p[0], rtol=0.0, atol=1e-12) else CurveSegment("cubic", p.copy())
    seg = CurveSegment("cubic", p.copy())
    if seg.is_straight:
        t = (p[1:3] - p[0]) @ chord / length2
        if np.all((t >= -1e-12) & (t <= 1.0 + 1e-12)):
            return CurveSegment("line", np.array([p[0], p[3]]))
    return seg


def _world(ob: bpy.types.Object, local: np.ndarray) -> np.ndarray:
    m = np.array(ob.matrix_world, dtype=np.float64)
    return local @ m[:3, :3].T + m[:3, 3]


def _spline_points(ob: bpy.types.Object, spline: bpy.types.Spline, where: str) -> tuple[str, list[np.ndarray]]:
    """World-space control polygons (BU, 3D) of the spline's segments: ``("bezier", [4x3...])`` or ``("poly", ...)``."""
    cyclic = bool(spline.use_cyclic_u)
    if spline.type == "BEZIER":
        n = len(spline.bezier_points)
        arrays = {}
        for key in ("co", "handle_left", "handle_right"):
            a = np.empty(n * 3, dtype=np.float64)
            spline.bezier_points.foreach_get(key, a)
            arrays[key] = _world(ob, a.reshape(n, 3))
        co, hl, hr = arrays["co"], arrays["handle_left"], arrays["handle_right"]
        idx = list(range(n - 1)) + ([n - 1] if cyclic and n > 1 else [])
        return "bezier", [np.array([co[i], hr[i], hl[(i + 1) % n], co[(i + 1) % n]]) for i in idx]
    if spline.type == "POLY":
        n = len(spline.points)
        a = np.empty(n * 4, dtype=np.float64)
        spline.points.foreach_get("co", a)
        co = _world(ob, a.reshape(n, 4)[:, :3])
        idx = list(range(n - 1)) + ([n - 1] if cyclic and n > 2 else [])
        return "poly", [np.array([co[i], co[(i + 1) % n]]) for i in idx]
    raise PatternError(
        f"{where} is a {spline.type} spline; only Bézier and Poly splines are supported "
        "(convert it with Curve ▸ Set Spline Type)"
    )


def curves_from_objects(
    objects: Iterable[bpy.types.Object],
    *,
    unit_scale: float | None = None,
    warnings: list[str] | None = None,
) -> list[CreaseCurve]:
    """Crease curves (mm, sheet plane XY) from the splines of curve objects with a crease role.

    Every spline of every role-carrying curve object becomes one :class:`CreaseCurve` with
    ``source = "curve '<object>' spline <k>"``; the object's world matrix is applied. Objects that are not curves
    or have no role are skipped and named in ``warnings`` (if a list is given). Raises :class:`PatternError` when
    nothing is left ("no crease curves selected"), for NURBS splines, or when the curves do not lie in one plane
    parallel to XY (naming the curve that leaves it).
    """
    scale = default_unit_scale() if unit_scale is None else float(unit_scale)
    if not scale > 0.0:
        raise PatternError(f"unit scale must be positive (Blender units per mm), got {unit_scale!r}")
    notes = warnings if warnings is not None else []
    collected: list[tuple[CreaseCurve, np.ndarray]] = []
    skipped: list[str] = []
    for ob in objects:
        if ob is None:
            continue
        role, magnitude = _role_and_angle(ob)
        if ob.type != "CURVE" or role == "NONE":
            skipped.append(ob.name)
            continue
        assignment = ROLE_ASSIGNMENT[role]
        angle = _signed_angle(role, magnitude)
        for k, spline in enumerate(ob.data.splines):
            where = f"curve '{ob.name}' spline {k}"
            kind, polygons = _spline_points(ob, spline, where)
            if not polygons:
                notes.append(f"{where}: fewer than two points, skipped")
                continue
            z = np.concatenate([p[:, 2] for p in polygons]) / scale
            segments: list[CurveSegment] = []
            for p in polygons:
                mm = p[:, :2] / scale
                seg = CurveSegment("line", mm) if kind == "poly" else _segment(mm)
                if seg is not None and not (seg.kind == "line" and np.array_equal(seg.points[0], seg.points[1])):
                    segments.append(seg)
            if not segments:
                notes.append(f"{where}: has zero length, skipped")
                continue
            curve = CreaseCurve(segments, assignment, angle, closed=bool(spline.use_cyclic_u), source=where)
            collected.append((curve, z))
    if skipped:
        shown = ", ".join(f"'{name}'" for name in skipped[:10]) + (", ..." if len(skipped) > 10 else "")
        notes.append(f"{len(skipped)} object(s) without a crease role (or not curves) skipped: {shown}")
    if not collected:
        raise PatternError(
            "no crease curves selected: select curve objects and give them a crease role "
            "(Curved Fold sidebar, or Object ▸ Set Crease Role)"
        )
    _check_plane(collected, scale)
    return [curve for curve, _ in collected]


def _check_plane(collected: list[tuple[CreaseCurve, np.ndarray]], scale: float) -> None:
    """Raise :class:`PatternError` unless all control points share one z (within :data:`PLANE_TOLERANCE`)."""
    xy = np.concatenate([np.concatenate([s.points for s in c.segments]) for c, _ in collected])
    size = max(float(np.ptp(xy, axis=0).max()), 1.0)
    tol = PLANE_TOLERANCE * size
    z0 = float(collected[0][1][0])
    for curve, z in collected:
        spread = float(np.ptp(z))
        if spread > tol:
            raise PatternError(
                f"{curve.source} is not flat: its points span {spread:.4g} mm in z; crease curves must lie in "
                "one plane parallel to XY (the sheet)"
            )
        if abs(float(z[0]) - z0) > tol:
            raise PatternError(
                f"{curve.source} lies at z = {float(z[0]):.4g} mm but {collected[0][0].source} at z = {z0:.4g} mm; "
                "all crease curves must lie in one plane parallel to XY (the sheet)"
            )


def read_blend_file(path: str | Path, *, unit_scale: float | None = None) -> list[CreaseCurve]:
    """Crease curves of every curve object with a role in the ``.blend`` file ``path``.

    The file's objects are *linked* (``bpy.data.libraries.load(link=True)``) and the library is removed again
    afterwards, so the file open in Blender is left as it was. The crease-role property group is registered for the
    duration if the add-on is not enabled (the command line). ``unit_scale`` defaults to the file's first scene.
    """
    path = Path(path)
    if not path.is_file():
        raise PatternError(f"{path}: no such file")
    registered_here = _ensure_properties()
    before_libraries = set(bpy.data.libraries)
    try:
        try:
            with bpy.data.libraries.load(str(path), link=True) as (data_from, data_to):
                data_to.objects = list(data_from.objects)
                data_to.scenes = list(data_from.scenes[:1])
        except OSError as exc:
            raise PatternError(f"{path}: cannot read as a .blend file ({exc})") from exc
        scale = unit_scale
        if scale is None:
            scenes = [s for s in data_to.scenes if s is not None]
            scale = default_unit_scale(scenes[0]) if scenes else default_unit_scale()
        objects = [ob for ob in data_to.objects if ob is not None and ob.type == "CURVE"]
        try:
            curves = curves_from_objects(objects, unit_scale=scale)
        except PatternError as exc:
            raise PatternError(f"{path}: {exc}") from exc
        return curves
    finally:
        for lib in set(bpy.data.libraries) - before_libraries:
            bpy.data.libraries.remove(lib)
        if registered_here:
            _release_properties()


register_blend_reader(read_blend_file)


def _ensure_properties() -> bool:
    """Register ``Object.curved_fold`` if the add-on is not enabled (plain ``bpy`` use); True if we did."""
    if hasattr(bpy.types.Object, "curved_fold"):
        return False
    from . import properties

    bpy.utils.register_class(properties.CurvedFoldObjectProperties)
    properties.register_extra()
    return True


def _release_properties() -> None:
    from . import properties

    properties.unregister_extra()
    bpy.utils.unregister_class(properties.CurvedFoldObjectProperties)


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


def objects_from_curves(
    curves: Iterable[CreaseCurve],
    collection: bpy.types.Collection,
    unit_scale: float | None = None,
) -> list[bpy.types.Object]:
    """One Bézier curve object per crease curve, linked into ``collection``, with role and fold angle set.

    The inverse of :func:`curves_from_objects` (lines and cubics exactly, arcs as ≤ 90° cubic pieces). Objects sit
    at the origin with the curve in the XY plane; ``unit_scale`` is Blender units per mm (scene default).
    """
    scale = default_unit_scale() if unit_scale is None else float(unit_scale)
    made: list[bpy.types.Object] = []
    try:
        for i, curve in enumerate(curves):
            pieces = [p for seg in curve.segments for p in segment_cubics(seg)]
            if not pieces:
                raise PatternError(f"{curve.source or f'curve {i}'}: has no segments")
            role = ASSIGNMENT_ROLE.get(curve.assignment)
            if role is None:
                raise PatternError(f"{curve.source or f'curve {i}'}: unknown assignment {curve.assignment!r}")
            cyclic = bool(curve.closed) and np.allclose(pieces[-1][3], pieces[0][0], rtol=0.0, atol=1e-9)
            n_knots = len(pieces) if cyclic else len(pieces) + 1
            # Knot j: co = start of piece j, handle_right = its first handle, handle_left = piece j-1's second handle.
            co = np.array([p[0] for p in pieces] + ([] if cyclic else [pieces[-1][3]]))
            right = np.array([p[1] for p in pieces] + ([] if cyclic else [pieces[-1][3]]))
            left = np.array([pieces[-1][2] if cyclic else pieces[0][0]] + [p[2] for p in pieces[: n_knots - 1]])

            def flat(a: np.ndarray) -> np.ndarray:
                return np.column_stack([a * scale, np.zeros(len(a))]).astype(np.float64).ravel()

            name = f"{role.title()} {i + 1:03d}"
            cu = bpy.data.curves.new(name, type="CURVE")
            cu.dimensions = "2D"
            spline = cu.splines.new("BEZIER")
            spline.bezier_points.add(n_knots - 1)
            for bp in spline.bezier_points:  # FREE first: setting co on AUTO handles would move the handles
                bp.handle_left_type = "FREE"
                bp.handle_right_type = "FREE"
            spline.bezier_points.foreach_set("co", flat(co))
            spline.bezier_points.foreach_set("handle_left", flat(left))
            spline.bezier_points.foreach_set("handle_right", flat(right))
            spline.use_cyclic_u = cyclic
            ob = bpy.data.objects.new(name, cu)
            collection.objects.link(ob)
            made.append(ob)
            props = ob.curved_fold
            if curve.fold_angle is not None and np.isfinite(curve.fold_angle) and role in ("MOUNTAIN", "VALLEY"):
                props.fold_angle = min(abs(float(curve.fold_angle)), 180.0)
            props.role = role
    except Exception:
        for ob in made:
            data = ob.data
            bpy.data.objects.remove(ob)
            if data.users == 0:
                bpy.data.curves.remove(data)
        raise
    return made
