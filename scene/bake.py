"""Bake a fold sequence to shape keys with keyed values, so playback and glTF export need no add-on.

One relative shape key per frame (``cf_frame_0001`` ...), Basis = the flat sheet. Key i is keyed 0 → 1 → 0 over
frames ``f[i-1], f[i], f[i+1]`` with LINEAR interpolation (the first key holds 1 before its frame, the last after),
so at any frame exactly one key is 1 and between frames two keys blend linearly. The crease-curve children get the
same keys, so the red/blue creases follow the animation.

Blender 5.0 creates shape keys with ``value = 1.0`` (4.5: 0.0), so every value is set explicitly. F-curves are
reached through the layered-action API (``bpy_extras.anim_utils.action_get_channelbag_for_slot``) with a
fallback to ``Action.fcurves`` where that API is missing.

Writes are atomic: :func:`bake_shape_keys` receives all frames already computed, and if writing fails part way
the keys and F-curves it created are removed before the exception propagates.
"""

from __future__ import annotations

from collections.abc import Sequence

import bpy
import numpy as np

from .mesh_object import _crease_curve_objects, crease_point_indices, mm_per_unit

KEY_PREFIX = "cf_frame_"


def key_name(frame: int) -> str:
    """Name of the shape key holding ``frame`` (``cf_frame_0001``; negative frames keep their sign)."""
    return f"{KEY_PREFIX}{frame:04d}"


def _fcurves(id_data: bpy.types.ID) -> list:
    """The F-curves animating ``id_data`` (a ``Key``), through the 5.0 channelbag API or the 4.x fallback."""
    anim = id_data.animation_data
    if anim is None or anim.action is None:
        return []
    action = anim.action
    try:
        from bpy_extras.anim_utils import action_get_channelbag_for_slot

        bag = action_get_channelbag_for_slot(action, anim.action_slot)
        return list(bag.fcurves) if bag is not None else []
    except (ImportError, AttributeError):  # pragma: no cover - Blender < 4.4
        return list(action.fcurves)


def _remove_fcurves(id_data: bpy.types.ID, names: set[str]) -> None:
    anim = id_data.animation_data
    if anim is None or anim.action is None:
        return
    action = anim.action
    try:
        from bpy_extras.anim_utils import action_get_channelbag_for_slot

        container = action_get_channelbag_for_slot(action, anim.action_slot)
    except (ImportError, AttributeError):  # pragma: no cover
        container = action
    if container is None:
        return
    for fc in list(container.fcurves):
        if fc.data_path.startswith('key_blocks["') and fc.data_path.split('"')[1] in names:
            container.fcurves.remove(fc)
    if not len(container.fcurves) and action.users <= 1:
        anim.action = None
        if action.users == 0:
            bpy.data.actions.remove(action)


def baked_frames(ob: bpy.types.Object) -> list[int]:
    """Frames baked on ``ob`` (from its ``cf_frame_*`` shape keys), in order."""
    keys = getattr(ob.data, "shape_keys", None)
    if keys is None:
        return []
    return sorted(int(k.name[len(KEY_PREFIX) :]) for k in keys.key_blocks if k.name.startswith(KEY_PREFIX))


def _clear_keys(ob: bpy.types.Object) -> None:
    keys = getattr(ob.data, "shape_keys", None)
    if keys is None:
        return
    names = {k.name for k in keys.key_blocks if k.name.startswith(KEY_PREFIX)}
    _remove_fcurves(keys, names)
    for name in names:
        ob.shape_key_remove(keys.key_blocks[name])
    keys = ob.data.shape_keys
    if keys is not None and len(keys.key_blocks) <= 1:
        ob.shape_key_clear()


def clear_bake(ob: bpy.types.Object) -> int:
    """Remove the baked keys and their F-curves from ``ob`` and its crease curves; returns the frames removed.

    The Basis is removed too when no other shape key remains; the mesh keeps the Basis shape.
    """
    n = len(baked_frames(ob))
    for child in _crease_curve_objects(ob).values():
        _clear_keys(child)
    _clear_keys(ob)
    return n


def _key_sequence(
    target: bpy.types.Object,
    frames: Sequence[int],
    basis: np.ndarray,
    shapes: Sequence[np.ndarray],
    write,
) -> None:
    """Add Basis (if missing) + one key per frame on ``target`` and key the values 0 → 1 → 0."""
    if target.data.shape_keys is None:
        b = target.shape_key_add(name="Basis", from_mix=False)
        write(b, basis)
    for shape, f in zip(shapes, frames, strict=True):
        k = target.shape_key_add(name=key_name(f), from_mix=False)
        k.value = 0.0
        write(k, shape)
    blocks = target.data.shape_keys.key_blocks
    for i, f in enumerate(frames):
        k = blocks[key_name(f)]
        for j, v in ((i - 1, 0.0), (i, 1.0), (i + 1, 0.0)):
            if 0 <= j < len(frames):
                k.value = v
                k.keyframe_insert("value", frame=frames[j])
        k.value = 0.0
    for fc in _fcurves(target.data.shape_keys):
        if fc.data_path.startswith(f'key_blocks["{KEY_PREFIX}'):
            for kp in fc.keyframe_points:
                kp.interpolation = "LINEAR"
            fc.update()


def bake_shape_keys(
    ob: bpy.types.Object,
    frames: Sequence[int],
    positions: Sequence[np.ndarray],
    *,
    basis: np.ndarray | None = None,
    scene: bpy.types.Scene | None = None,
) -> list[str]:
    """Bake ``positions[i]`` (``(n, 3)`` mm) at ``frames[i]`` into shape keys on ``ob``; return the key names.

    A previous bake is replaced. ``basis`` (mm) defaults to the flat sheet from the ``cf_flat`` attribute (z = 0)
    or, without it, the current vertex positions. All-or-nothing: on failure the new keys are removed again.
    """
    frames = [int(f) for f in frames]
    if len(frames) != len(positions):
        raise ValueError(f"{len(frames)} frames but {len(positions)} position arrays")
    if len(set(frames)) != len(frames):
        raise ValueError(f"frames must be distinct, got {frames}")
    me = ob.data
    n = len(me.vertices)
    scale = 1.0 / mm_per_unit(scene)
    shapes = []
    for i, p in enumerate(positions):
        p = np.asarray(p, dtype=np.float64)
        if p.shape != (n, 3) or not np.all(np.isfinite(p)):
            raise ValueError(f"frame {frames[i]}: positions must be finite with shape ({n}, 3), got {p.shape}")
        shapes.append((p * scale).astype(np.float32))
    if basis is None:
        flat = me.attributes.get("cf_flat")
        base = np.zeros((n, 3), dtype=np.float32)
        if flat is not None:
            xy = np.empty(2 * n, dtype=np.float32)
            flat.data.foreach_get("vector", xy)
            base[:, :2] = xy.reshape(-1, 2) * scale
        else:
            me.attributes["position"].data.foreach_get("vector", base.ravel())
    else:
        base = (np.asarray(basis, dtype=np.float64).reshape(n, 3) * scale).astype(np.float32)

    clear_bake(ob)

    def write_mesh(key, co):
        key.points.foreach_set("co", np.ascontiguousarray(co).ravel())

    children = list(_crease_curve_objects(ob).values())
    try:
        _key_sequence(ob, frames, base, shapes, write_mesh)
        for child in children:
            idx = crease_point_indices(child)

            def write_curve(key, co, idx=idx):
                key.data.foreach_set("co", np.ascontiguousarray(co[idx]).ravel())

            _key_sequence(child, frames, base, shapes, write_curve)
    except Exception:
        clear_bake(ob)
        raise
    me.update()
    return [key_name(f) for f in frames]
