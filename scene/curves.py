"""Crease curves drawn in Blender ↔ the engine's :class:`~..core.pattern.CreaseCurve` (paper §3.1: the input).

* :func:`curves_from_objects` reads Bézier and Poly splines of curve objects that have a crease role
  (``Object.curved_fold``, see :mod:`.properties`), in world space, as exact segments in millimetres. A spline an
  import wrote and nobody edited gives back the file's own strokes (arcs as arcs, double precision, file order;
  :mod:`.exact_curves`); :func:`stored_pattern` gives back an unedited FOLD import's pattern.
* :func:`read_blend_file` does the same for every role-carrying curve object of a ``.blend`` file on disk (the
  ``.blend`` input of ``core.io.reader``), without changing the file open in Blender.
* :func:`objects_from_curves` is the inverse, used by the Import operator: one curve object per role and fold
  angle, one spline per chain of strokes (Poly for lines only, else Bézier with arcs as ≤ 90° cubic pieces).

Units: the engine works in millimetres, Blender in Blender units (BU); 1 BU = 1000 mm × the scene's
``unit_settings.scale_length``. ``unit_scale`` everywhere in this module is **Blender units per millimetre**
(default ``1 / (1000 × scale_length)``), so ``BU = mm × unit_scale`` and ``mm = BU / unit_scale``.

A Bézier spline's segment i runs from ``co[i]`` through ``handle_right[i]`` and ``handle_left[i+1]`` to
``co[i+1]`` (a cubic), plus the closing segment ``n-1 → 0`` when the spline is cyclic — exactly the curve Blender
draws. A cubic whose handles lie on its chord, between its ends, is a straight line and becomes a ``"line"``
segment, so straight creases stay straight (the ruling-aware swaps treat them differently from curves); the test
allows a few float32 steps (:data:`STRAIGHT_TOLERANCE`), as Blender stores control points in single precision.
"""

from __future__ import annotations

import math
import time
from collections.abc import Generator, Iterable
from pathlib import Path

import bpy
import numpy as np

from ..core import run_to_end
from ..core.io.reader import register_blend_reader
from ..core.pattern.model import CreaseCurve, CurveSegment, PatternError
from . import exact_curves
from .properties import ASSIGNMENT_ROLE, ROLE_ASSIGNMENT
from .single_precision import as_typed

READ_UNIT_MS = 30.0
"""Work per unit of :func:`curves_steps` (ms): a Blender job's slice runs whole units."""

PLANE_TOLERANCE = 1e-3
"""Allowed spread of z (relative to the pattern's size, at least 1 mm) for curves to count as one XY plane; the fold
takes their x and y. A spread of a thousandth of the sheet changes a curve's length by at most ~5e-7 of it,
far below any strain we report; 1e-5 refused curves with 10–20 µm of z noise on a 150 mm sheet (a designer
session), which no one drawing in the viewport can see."""

STRAIGHT_TOLERANCE = 8.0 * float(np.finfo(np.float32).eps)
"""A Bézier piece whose handles lie this close to its chord (relative to its size) is a straight line: float32
control points put handles drawn on the chord a few float32 steps off it."""

ANGLE_DECIMALS = 4
"""Fold angles are read to 0.0001°: the float32 radians Blender stores put a typed 90° at 89.999997°."""


def default_unit_scale(scene: bpy.types.Scene | None = None) -> float:
    """Blender units per millimetre in ``scene`` (the context scene by default): ``1 / (1000 × scale_length)``."""
    scene = scene or bpy.context.scene
    # scale_length is a float32 (0.001 reads back as 0.0010000000475): a typed-in 0.001 means exactly 1 BU = 1 mm
    scale = as_typed(scene.unit_settings.scale_length) if scene is not None else 1.0
    return 1.0 / (1000.0 * (scale if scale > 0.0 else 1.0))


def curve_objects(objects) -> list[bpy.types.Object]:
    """The curve objects among ``objects`` that carry a crease role (others, e.g. crease-display curves, are not)."""
    out = []
    for ob in objects:
        if ob is None or ob.type != "CURVE" or "cf_crease_role" in ob:
            continue
        props = getattr(ob, "curved_fold", None)
        if props is not None and getattr(props, "role", "NONE") == "NONE":
            continue
        out.append(ob)
    return out


def shown_crease_curves(collection: bpy.types.Collection, layer=None) -> tuple[list[bpy.types.Object], list[str]]:
    """The crease curves of ``collection`` (and the collections in it) that the viewport shows, and a warning naming
    those it hides: hidden (H) or disabled in viewports, or in a collection inside ``collection`` that is hidden,
    disabled or excluded in the view layer ``layer`` (default: the current one). A fold of a collection folds what
    the designer sees (a crease hidden with H, or in a hidden sub-collection, was folded too; a designer session);
    the chosen collection's own visibility does not count, it was chosen. The command line reads a .blend file's
    collection the same way (:func:`_blend_objects`)."""
    if layer is None:
        layer = getattr(bpy.context, "view_layer", None)
    every = curve_objects(collection.all_objects)
    hidden = _hidden_below(collection, layer)
    kept = [ob for ob in every if ob.name not in hidden]
    return kept, _hidden_note([ob.name for ob in every if ob.name in hidden], f"'{collection.name}'")


def _hidden_note(names: list[str], where: str) -> list[str]:
    """The warning naming the hidden crease curves ``names`` of ``where`` left out of a fold (none if none)."""
    if not names:
        return []
    listed = ", ".join(f"'{n}'" for n in names[:10]) + (", ..." if len(names) > 10 else "")
    return [f"{len(names)} hidden crease curve(s) of {where} left out: {listed} (show them to fold them)"]


def _hidden_below(collection: bpy.types.Collection, layer) -> set[str]:
    """Names of the objects of ``collection`` the viewport hides in the view layer ``layer``: hidden (H), disabled
    in viewports, or only in collections below ``collection`` that are excluded, hidden or disabled there (one also
    linked into a shown collection is shown: a review session's crease in both was left out)."""
    hidden = {ob.name for ob in collection.all_objects if ob.hide_viewport or _hidden_in(ob, layer)}
    top = _layer_collection(layer.layer_collection, collection) if layer is not None else None
    if top is None:
        return hidden
    shown = {ob.name for ob in collection.objects}
    stack = [(child, False) for child in top.children]
    while stack:
        lc, unseen = stack.pop()
        unseen = unseen or lc.exclude or lc.hide_viewport or lc.collection.hide_viewport
        if not unseen:
            shown.update(ob.name for ob in lc.collection.objects)
        stack.extend((child, unseen) for child in lc.children)
    return hidden | ({ob.name for ob in collection.all_objects} - shown)


def _layer_collection(root, collection: bpy.types.Collection):
    """The layer collection of ``collection`` under ``root`` (a view layer's tree), or None."""
    stack = [root]
    while stack:
        lc = stack.pop()
        if lc.collection == collection:
            return lc
        stack.extend(lc.children)
    return None


def _role_and_angle(ob: bpy.types.Object) -> tuple[str, float]:
    props = getattr(ob, "curved_fold", None)
    if props is None:
        return "NONE", 180.0
    return props.role, round(math.degrees(props.fold_angle), ANGLE_DECIMALS)


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
    # Blender stores control points in float32: handles placed on the chord land up to a few float32 steps off it
    length = math.sqrt(length2)
    off = np.abs(chord[0] * (p[1:3, 1] - p[0, 1]) - chord[1] * (p[1:3, 0] - p[0, 0])) / length
    slack = STRAIGHT_TOLERANCE * max(length, float(np.abs(p).max()))
    if np.all(off <= slack):
        t = (p[1:3] - p[0]) @ chord / length2
        if np.all((t >= -STRAIGHT_TOLERANCE) & (t <= 1.0 + STRAIGHT_TOLERANCE)):
            return CurveSegment("line", np.array([p[0], p[3]]))
    return seg


def world_matrix(ob: bpy.types.Object) -> np.ndarray:
    """``ob``'s world matrix (4×4): Blender's ``matrix_world``, except for an object linked from a library file
    into no scene of this file (:func:`read_blend_file`), which Blender never evaluates (its ``matrix_world`` is the
    identity): there it is composed as Blender does, parent's world × parent inverse × own transform (location,
    rotation, scale and their deltas); constraints are left out."""
    if ob.library is None or any(scene.library is None for scene in ob.users_scene):
        return np.array(ob.matrix_world, dtype=np.float64)
    m = np.array(ob.matrix_basis, dtype=np.float64)
    if ob.parent is not None:
        m = world_matrix(ob.parent) @ np.array(ob.matrix_parent_inverse, dtype=np.float64) @ m
    return m


def _world(ob: bpy.types.Object, local: np.ndarray) -> np.ndarray:
    m = world_matrix(ob)
    return local @ m[:3, :3].T + m[:3, 3]


def _warn_unread_shape(ob: bpy.types.Object, notes: list[str]) -> None:
    """Warn when the viewport draws ``ob`` other than its splines: modifiers (Mirror, Array, Hook …) and shape keys
    change what is shown, while the creases are the splines as drawn (an evaluated curve is a mesh, without the
    exact segments the ruling-aware meshing needs)."""
    shown = [m.name for m in ob.modifiers if m.show_viewport]
    if shown:
        notes.append(
            f"curve '{ob.name}': its modifier(s) {', '.join(repr(n) for n in shown[:4])} are not folded — the "
            "creases are its splines as drawn (draw the copies as splines, or disable the modifiers)"
        )
    keys = ob.data.shape_keys
    if keys is not None and any(k.value != 0.0 and not k.mute for k in keys.key_blocks[1:]):
        notes.append(
            f"curve '{ob.name}': its shape keys are not folded — the creases are the splines as drawn, without "
            "the keys (set the key values to 0, or make the shape the drawn one)"
        )


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
    return run_to_end(curves_steps(objects, unit_scale=unit_scale, warnings=warnings))


def curves_steps(
    objects: Iterable[bpy.types.Object],
    *,
    unit_scale: float | None = None,
    warnings: list[str] | None = None,
    unit_ms: float = READ_UNIT_MS,
) -> Generator[None, None, list[CreaseCurve]]:
    """:func:`curves_from_objects` in units of about ``unit_ms`` for a Blender job: yields between splines once
    that much time has passed, returns the curves. (Reading the 1,600 splines of CircularPleat-antiFacet takes
    ~180 ms, which in one unit froze the interface.)"""
    last = time.perf_counter()
    scale = default_unit_scale() if unit_scale is None else float(unit_scale)
    if not scale > 0.0:
        raise PatternError(f"unit scale must be positive (Blender units per mm), got {unit_scale!r}")
    notes = warnings if warnings is not None else []
    collected: list[tuple[CreaseCurve, np.ndarray, tuple[str, int] | None]] = []
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
        _warn_unread_shape(ob, notes)
        stored = exact_curves.read_description(ob.data)
        if stored is not None and stored.role == role and stored.angle is not None and role in ("MOUNTAIN", "VALLEY"):
            if np.float32(math.radians(abs(stored.angle))) == np.float32(ob.curved_fold.fold_angle):
                angle = float(stored.angle)  # the file's angle in double precision (the property is float32)
        transform = None
        if stored is not None:
            transform = exact_curves.similarity(world_matrix(ob), stored.unit_scale, scale)
        for k, spline in enumerate(ob.data.splines):
            if 1e3 * (time.perf_counter() - last) >= unit_ms:
                yield
                last = time.perf_counter()
            where = f"curve '{ob.name}' spline {k}"
            kind, polygons = _spline_points(ob, spline, where)
            if not polygons:
                notes.append(f"{where}: fewer than two points, skipped")
                continue
            z = np.concatenate([p[:, 2] for p in polygons]) / scale
            strokes = None
            if transform is not None and k < len(stored.splines):
                strokes = _unedited_strokes(spline, stored.splines[k], stored.unit_scale)
            if strokes is not None:
                identity = np.array_equal(transform, np.eye(3))
                for stroke in strokes:
                    segs = stroke.segments
                    if not identity:
                        segs = [exact_curves.transform_segment(g, transform) for g in segs]
                    source = f"{where} ({stroke.source})" if stroke.source else where
                    curve = CreaseCurve(
                        segs, assignment, angle, closed=stroke.closed, source=source, sampled=stroke.sampled
                    )
                    collected.append((curve, z, (stored.import_id, stroke.index)))
                continue
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
            collected.append((curve, z, None))
    if skipped:
        shown = ", ".join(f"'{name}'" for name in skipped[:10]) + (", ..." if len(skipped) > 10 else "")
        notes.append(f"{len(skipped)} object(s) without a crease role (or not curves) skipped: {shown}")
    if not collected:
        raise PatternError(
            "no crease curves selected: select curve objects and give them a crease role "
            "(Curved Fold sidebar, or Object ▸ Curved Fold ▸ Set Crease Role)"
        )
    keys = [key for _, _, key in collected]
    if all(key is not None for key in keys) and len({key[0] for key in keys}) == 1:
        collected.sort(key=lambda item: item[2][1])  # one unedited import: the file's order, as the command line
    _check_plane([(curve, z) for curve, z, _ in collected], scale)
    return [curve for curve, _, _ in collected]


def stored_pattern(
    objects: Iterable[bpy.types.Object],
    *,
    unit_scale: float | None = None,
    interval: float | None = None,
    tolerance: float | None = None,
):
    """The discretised pattern of a FOLD import when ``objects`` are exactly its curve objects, unedited (every
    spline as imported, roles and angles as imported, all placed alike by a similarity): the file's own pattern,
    which the command line folds without re-discretising; another tool's file sampled at ``interval`` and
    ``tolerance`` (mm, ``None`` automatic), as the command line samples it at ``--interval`` and ``--tolerance``
    (:func:`..core.pattern.discretize.segments_at_interval`). ``None`` otherwise (then the curves are
    discretised)."""
    scale = default_unit_scale() if unit_scale is None else float(unit_scale)
    objects = [ob for ob in objects if ob is not None]
    if not objects or any(ob.type != "CURVE" for ob in objects):
        return None
    stored = [exact_curves.read_pattern_json(ob.data) for ob in objects]
    if any(s is None for s in stored) or len({s.import_id for s in stored}) != 1 or stored[0].objects != len(objects):
        return None
    if len({ob.data.name for ob in objects}) != len(objects):
        return None
    matrix = world_matrix(objects[0])
    transform = None
    for ob in objects:
        desc = exact_curves.read_description(ob.data)
        role, _ = _role_and_angle(ob)
        if desc is None or desc.import_id != stored[0].import_id or desc.role != role:
            return None
        if desc.angle is not None and role in ("MOUNTAIN", "VALLEY"):
            if np.float32(math.radians(abs(desc.angle))) != np.float32(ob.curved_fold.fold_angle):
                return None
        if not np.array_equal(world_matrix(ob), matrix):
            return None
        transform = exact_curves.similarity(matrix, desc.unit_scale, scale)
        if transform is None or len(ob.data.splines) != len(desc.splines):
            return None
        for spline, strokes in zip(ob.data.splines, desc.splines, strict=True):
            if _unedited_strokes(spline, strokes, desc.unit_scale) is None:
                return None
    pattern = exact_curves.pattern_from_json(stored[0], None if np.array_equal(transform, np.eye(3)) else transform)
    if stored[0].segments:
        from ..core.pattern.discretize import segments_at_interval

        pattern = segments_at_interval(pattern, interval, tolerance)
    return pattern


def _unedited_strokes(spline: bpy.types.Spline, strokes: list, unit_scale: float) -> list | None:
    """The stored strokes of ``spline`` if its control points are still those the import wrote, else ``None``."""
    segments = [g for s in strokes for g in s.oriented()]
    poly = exact_curves.is_poly(segments)
    if spline.type != ("POLY" if poly else "BEZIER"):
        return None
    cyclic = bool(spline.use_cyclic_u)
    if poly:
        n = len(spline.points)
        a = np.empty(n * 4, dtype=np.float64)
        spline.points.foreach_get("co", a)
        local = a.reshape(n, 4)[:, :3]
    else:
        n = len(spline.bezier_points)
        parts = []
        for key in ("co", "handle_left", "handle_right"):
            a = np.empty(n * 3, dtype=np.float64)
            spline.bezier_points.foreach_get(key, a)
            parts.append(a.reshape(n, 3))
        local = np.concatenate(parts)
    if np.any(local[:, 2] != 0.0):
        return None
    expected = exact_curves.expected_local(strokes, cyclic, poly, unit_scale)
    return strokes if exact_curves.unchanged(local[:, :2], expected) else None


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


def read_blend_file(
    path: str | Path, *, unit_scale: float | None = None, collection: str | None = None
) -> tuple[list[CreaseCurve], list[str]]:
    """Crease curves of a ``.blend`` file on disk, and the warnings met reading them: the role-carrying curves of
    ``collection`` (and the collections in it), or else of the file's (first) scene — not those in collections
    excluded from its view layer, nor curves in no scene.

    The file's objects are *linked* (``bpy.data.libraries.load(link=True)``) and the library is removed again
    afterwards, so the file open in Blender is left as it was. Linked objects are in no scene here, so their world
    matrices are composed from their transforms and parents (:func:`world_matrix`), as Blender shows them. The
    crease-role property group is registered for the duration if the add-on is not enabled (the command line).
    ``unit_scale`` defaults to the file's first scene.
    """
    path = Path(path)
    if not path.is_file():
        raise PatternError(f"{path}: no such file")
    registered_here = _ensure_properties()
    before_libraries = set(bpy.data.libraries)
    warnings: list[str] = []
    try:
        try:
            with bpy.data.libraries.load(str(path), link=True) as (data_from, data_to):
                data_to.objects = list(data_from.objects)
                data_to.collections = list(data_from.collections)
                data_to.scenes = list(data_from.scenes[:1])
        except OSError as exc:
            why = " ".join(str(exc).split())  # Blender's message ends in a newline: one line (a CLI review session)
            raise PatternError(f"{path}: cannot read as a .blend file ({why})") from exc
        scenes = [s for s in data_to.scenes if s is not None]
        scale = unit_scale
        if scale is None:
            scale = default_unit_scale(scenes[0]) if scenes else default_unit_scale()
        objects = _blend_objects(path, data_to, scenes[0] if scenes else None, collection, warnings)
        if not objects:
            where = f"collection '{collection}'" if collection is not None else "the file's scene"
            raise PatternError(f"{path.name}: no crease curves (curve objects with a crease role) in {where}")
        try:
            curves = curves_from_objects(objects, unit_scale=scale, warnings=warnings)
        except PatternError as exc:
            raise PatternError(f"{path}: {exc}") from exc
        return curves, warnings
    finally:
        for lib in set(bpy.data.libraries) - before_libraries:
            bpy.data.libraries.remove(lib)
        if registered_here:
            _release_properties()


def _blend_objects(path: Path, data, scene, collection: str | None, warnings: list[str]) -> list[bpy.types.Object]:
    """The curve objects of a linked .blend file (``data``: what was linked) that :func:`read_blend_file` reads:
    those of ``collection``, or of ``scene`` less the view layer's excluded collections; warnings name what is
    left out, objects whose placement the file does not hold (constraints, non-object parents), and a file whose
    borders lie in several collections (several patterns folded as one sheet)."""
    curves = curve_objects(data.objects)
    if collection is not None:
        chosen = next((c for c in data.collections if c is not None and c.name == collection), None)
        if chosen is None:
            names = sorted(c.name for c in data.collections if c is not None)
            shown = ", ".join(f"'{n}'" for n in names[:10]) + (", ..." if len(names) > 10 else "")
            raise PatternError(f"{path.name}: no collection named '{collection}' (the file has {shown or 'none'})")
        members = {ob.name for ob in chosen.all_objects}
        layer = scene.view_layers[0] if scene is not None and scene.view_layers else None
        hidden = _hidden_below(chosen, layer)
        kept = [ob for ob in curves if ob.name in members and ob.name not in hidden]
        unseen = [ob.name for ob in curves if ob.name in members and ob.name in hidden]
        warnings += _hidden_note(unseen, f"'{collection}'")
    elif scene is not None:
        visible, excluded, hidden = _shown_in(scene)
        kept = [ob for ob in curves if ob.name in visible and ob.name not in hidden]
        left = [ob.name for ob in curves if ob.name not in visible]
        unseen = [ob.name for ob in curves if ob.name in visible and ob.name in hidden]
        warnings += _hidden_note(unseen, f"scene '{scene.name}'")
        if left:
            where = (
                f" (in {', '.join(repr(c.name) for c in excluded)}, excluded from the view layer)" if excluded else ""
            )
            warnings.append(
                f"{len(left)} crease curve(s) not in scene '{scene.name}' left out{where}: "
                + ", ".join(f"'{n}'" for n in left[:10])
                + (", ..." if len(left) > 10 else "")
                + "; pass --collection to fold another collection"
            )
    else:
        kept = curves
    for ob in kept:
        _warn_placement(ob, warnings)
    if collection is None:
        holders = sorted({c.name for ob in kept if _role_and_angle(ob)[0] == "BORDER" for c in ob.users_collection})
        if len(holders) > 1:
            warnings.append(
                f"border curves lie in {len(holders)} collections ("
                + ", ".join(f"'{n}'" for n in holders[:6])
                + "), folded together as one sheet; pass --collection NAME to fold one pattern"
            )
    return kept


def _shown_in(scene) -> tuple[set[str], list[bpy.types.Collection], set[str]]:
    """The names of the objects ``scene`` holds — in its collection or in one not excluded (the checkbox) from its
    first view layer, nor inside an excluded one —, the excluded collections (one walk of the layer tree), and the
    names of those of them the viewport hides: hidden (H) or disabled in viewports, or in a collection hidden or
    disabled there (as ``Object.visible_get`` tells in Blender, which a linked file's objects cannot be asked)."""
    if not scene.view_layers:
        return {ob.name for ob in scene.collection.all_objects}, [], set()
    layer = scene.view_layers[0]
    shown: set[str] = set()
    hidden: set[str] = set()
    seen: set[str] = set()
    excluded: list[bpy.types.Collection] = []
    stack = [(layer.layer_collection, False)]  # its collection is the scene's own
    while stack:
        lc, unseen = stack.pop()
        if lc.exclude:
            excluded.append(lc.collection)
            continue
        unseen = unseen or lc.hide_viewport or lc.collection.hide_viewport
        for ob in lc.collection.objects:
            shown.add(ob.name)
            if unseen or ob.hide_viewport or _hidden_in(ob, layer):
                hidden.add(ob.name)
            else:
                seen.add(ob.name)  # in a shown collection: shown, whatever other collections hold it
        stack.extend((child, unseen) for child in lc.children)
    return shown, excluded, hidden - seen


def _hidden_in(ob: bpy.types.Object, layer) -> bool:
    """Whether ``ob`` is hidden (H) in the view layer ``layer``."""
    try:
        return bool(ob.hide_get(view_layer=layer))
    except (RuntimeError, TypeError):
        return False


def _warn_placement(ob: bpy.types.Object, warnings: list[str]) -> None:
    """Warn when a linked object's place is not its transforms and parents alone (:func:`world_matrix`)."""
    chain = ob
    while chain is not None:
        if any(getattr(c, "enabled", True) and not getattr(c, "mute", False) for c in chain.constraints):
            warnings.append(
                f"curve '{ob.name}': the constraints of '{chain.name}' are not applied when a .blend file is read "
                "(apply them: Object ▸ Apply ▸ Visual Transform)"
            )
            return
        if chain.parent is not None and chain.parent_type != "OBJECT":
            warnings.append(
                f"curve '{ob.name}': its {chain.parent_type.lower()} parent is not applied when a .blend file is "
                "read (parent it to an object, or apply the parent: Alt+P ▸ Clear and Keep Transformation)"
            )
            return
        chain = chain.parent


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


def _object_name(role: str, angle: float | None) -> str:
    """``"Mountain 180°"``, ``"Valley 54°"``, ``"Border"``: what the objects of one import are called."""
    if role in ("MOUNTAIN", "VALLEY") and angle is not None and np.isfinite(angle):
        return f"{role.title()} {abs(float(angle)):.4g}°"
    return role.title()


Chained = tuple[dict[tuple[str, float | None], list[list[tuple[int, bool]]]], float]
"""Strokes grouped by role and fold angle, each group's chains (``exact_curves.chain_strokes``), and the quantum
(mm) their ends were matched to: what :func:`objects_from_curves` writes as curve objects."""


def chain_steps(curves: list[CreaseCurve]) -> Generator[str, None, Chained]:
    """The curve objects an import makes of ``curves``, worked out without touching the scene, a group per unit of
    work (an import job's slices): one group per role and fold angle, its strokes chained end to end."""
    groups: dict[tuple[str, float | None], list[int]] = {}
    for i, curve in enumerate(curves):
        where = curve.source or f"curve {i}"
        if not curve.segments:
            raise PatternError(f"{where}: has no segments")
        role = ASSIGNMENT_ROLE.get(curve.assignment)
        if role is None:
            raise PatternError(f"{where}: unknown assignment {curve.assignment!r}")
        angle = curve.fold_angle if role in ("MOUNTAIN", "VALLEY", "FACET") else None
        if angle is not None and not np.isfinite(angle):
            angle = None
        groups.setdefault((role, None if angle is None else float(angle)), []).append(i)
    if not curves:
        return {}, 1e-9
    every = np.concatenate([s.points for c in curves for s in c.segments])
    quantum = max(float(np.ptp(every, axis=0).max()), 1.0) * 1e-9
    chains = {}
    for key, indices in groups.items():
        chains[key] = exact_curves.chain_strokes(curves, indices, quantum)
        yield "chains"
    return chains, quantum


def objects_from_curves(
    curves: Iterable[CreaseCurve],
    collection: bpy.types.Collection,
    unit_scale: float | None = None,
    *,
    import_name: str = "pattern",
    pattern=None,
    segments: bool = False,
    chained: Chained | None = None,
) -> list[bpy.types.Object]:
    """The crease curves as a handful of curve objects in ``collection``: one per role and fold angle.

    Strokes of one role and angle joined end to end become one spline (``exact_curves.chain_strokes``): a Poly
    spline when they are all lines (lines stay lines), else a Bézier spline (cubics exactly, arcs as ≤ 90° cubic
    pieces). The exact strokes are stored on each curve datablock (``exact_curves``) so that reading the objects
    back gives the file's own curves, in file order, while the splines are unedited. Objects sit at the origin in
    the XY plane; ``unit_scale`` is Blender units per mm (scene default). Creates nothing if a curve is unusable.

    ``pattern`` is the discretised pattern the curves were chained from (a FOLD file): stored too, so that the
    unedited objects fold to that very pattern (:func:`stored_pattern`), as the command line folds a FOLD file.
    ``segments``: ``pattern`` is another tool's segments, not yet sampled; a fold samples them at its interval.
    ``chained``: :func:`chain_steps`' result, if the caller worked it out already (an import job).
    """
    curves = list(curves)
    scale = default_unit_scale() if unit_scale is None else float(unit_scale)
    if chained is None:
        chained = run_to_end(chain_steps(curves))
    if not curves:
        return []
    groups, quantum = chained
    import_id = exact_curves.new_import_id(import_name)
    made: list[bpy.types.Object] = []
    try:
        for (role, angle), chains in groups.items():
            name = _object_name(role, angle)
            cu = bpy.data.curves.new(name, type="CURVE")
            cu.dimensions = "2D"
            stored: list[list[exact_curves.Stroke]] = []
            for chain in chains:
                strokes = [
                    exact_curves.Stroke(
                        i, curves[i].source, bool(curves[i].closed), rev, list(curves[i].segments), curves[i].sampled
                    )
                    for i, rev in chain
                ]
                _add_spline(cu, strokes, scale, quantum)
                stored.append(strokes)
            cu[exact_curves.EXACT_KEY] = exact_curves.description(import_id, scale, role, angle, stored)
            ob = bpy.data.objects.new(name, cu)
            collection.objects.link(ob)
            made.append(ob)
            props = ob.curved_fold
            if angle is not None and role in ("MOUNTAIN", "VALLEY"):
                props.fold_angle = math.radians(min(abs(angle), 180.0))
            props.role = role
        if pattern is not None:
            text = exact_curves.pattern_json(import_id, len(made), pattern, segments=segments)
            for ob in made:
                ob.data[exact_curves.PATTERN_KEY] = text
    except Exception:
        for ob in made:
            data = ob.data
            bpy.data.objects.remove(ob)
            if data.users == 0:
                bpy.data.curves.remove(data)
        raise
    return made


def _is_cyclic(strokes: list[exact_curves.Stroke], quantum: float) -> bool:
    segments = [g for s in strokes for g in s.oriented()]
    gap = np.abs(np.asarray(segments[-1].end) - np.asarray(segments[0].start)).max()
    return bool(gap <= quantum) and (len(segments) > 1)


def _add_spline(cu: bpy.types.Curve, strokes: list[exact_curves.Stroke], scale: float, quantum: float) -> None:
    """One spline through ``strokes`` (in their chained direction), written so that
    :func:`exact_curves.expected_local` gives back exactly what is stored."""
    segments = [g for s in strokes for g in s.oriented()]
    cyclic = _is_cyclic(strokes, quantum)
    poly = exact_curves.is_poly(segments)
    flat = exact_curves.expected_local(strokes, cyclic, poly, scale)
    if poly:
        spline = cu.splines.new("POLY")
        spline.points.add(len(flat) - 1)
        spline.points.foreach_set("co", np.column_stack([flat, np.zeros(len(flat)), np.ones(len(flat))]).ravel())
    else:
        n = len(flat) // 3
        spline = cu.splines.new("BEZIER")
        spline.bezier_points.add(n - 1)
        for bp in spline.bezier_points:  # FREE first: setting co on AUTO handles would move the handles
            bp.handle_left_type = "FREE"
            bp.handle_right_type = "FREE"
        for key, part in zip(
            ("co", "handle_left", "handle_right"), (flat[:n], flat[n : 2 * n], flat[2 * n :]), strict=True
        ):
            spline.bezier_points.foreach_set(key, np.column_stack([part, np.zeros(n)]).ravel())
    spline.use_cyclic_u = cyclic
