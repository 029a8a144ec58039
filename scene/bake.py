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
from dataclasses import dataclass
from dataclasses import field as dc_field

import bpy
import numpy as np

from .mesh_object import (
    _crease_curve_objects,
    child_points,
    crease_point_indices,
    flat_rescale,
    local_offset,
    mm_per_unit,
)

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
    offset = local_offset(ob)  # the engine's frame → object space, however the origin was moved
    shapes = []
    for i, p in enumerate(positions):
        p = np.asarray(p, dtype=np.float64)
        if p.shape != (n, 3) or not np.all(np.isfinite(p)):
            raise ValueError(f"frame {frames[i]}: positions must be finite with shape ({n}, 3), got {p.shape}")
        shapes.append((p * scale + offset).astype(np.float32))
    if basis is None:
        flat = me.attributes.get("cf_flat")
        base = np.zeros((n, 3), dtype=np.float32)
        if flat is not None:
            xy = np.empty(2 * n, dtype=np.float32)
            flat.data.foreach_get("vector", xy)
            base[:, :2] = xy.reshape(-1, 2) * (scale * flat_rescale(me, scene))
            base += offset.astype(np.float32)
        else:
            me.attributes["position"].data.foreach_get("vector", base.ravel())
    else:
        base = (np.asarray(basis, dtype=np.float64).reshape(n, 3) * scale + offset).astype(np.float32)

    clear_bake(ob)

    def write_mesh(key, co):
        key.points.foreach_set("co", np.ascontiguousarray(co).ravel())

    children = list(_crease_curve_objects(ob).values())
    try:
        _key_sequence(ob, frames, base, shapes, write_mesh)
        for child in children:
            idx = crease_point_indices(child)

            def write_curve(key, co, idx=idx, child=child):
                key.data.foreach_set("co", np.ascontiguousarray(child_points(child, co[idx])).ravel())

            _key_sequence(child, frames, base, shapes, write_curve)
    except Exception:
        clear_bake(ob)
        raise
    me.update()
    return [key_name(f) for f in frames]


def clear(ob: bpy.types.Object) -> int:
    """The Clear Bake operator's one scene call: remove the bake (keys, F-curves, an out-of-date mark and the mesh
    it kept) and reset the baked-frame count; returns the frames removed."""
    n = clear_bake(ob)
    forget_stale(ob)
    ob.curved_fold_mesh.baked_frames = 0
    return n


# ------------------------------------------------------------------------------------------ out-of-date bakes

STALE_KEY = "cf_bake_stale"
"""Object ID property: the bake no longer matches the fold (a live re-fold changed it); Re-bake is offered."""
STALE_MESH_KEY = "cf_stale_bake_mesh"
"""Object ID property: name of the previous mesh datablock that still holds an out-of-date bake (live re-mesh)."""


def is_stale(ob: bpy.types.Object) -> bool:
    """Whether ``ob`` has a bake that is out of date (kept, muted, Re-bake offered)."""
    return bool(ob.get(STALE_KEY, False))


def mark_stale(ob: bpy.types.Object) -> None:
    """Mark ``ob``'s bake out of date: its keys stay but are muted, so the live fold shows; Re-bake replaces them."""
    ob[STALE_KEY] = True
    keys = getattr(ob.data, "shape_keys", None)
    if keys is not None:
        for k in keys.key_blocks:
            if k.name.startswith(KEY_PREFIX):
                k.mute = True


def keep_stale_mesh(ob: bpy.types.Object) -> str:
    """Before a live re-mesh replaces ``ob``'s mesh: keep the old mesh (it holds the bake) under a fake user, named
    "<name> (out-of-date bake)"; returns the name the new mesh should take."""
    me = ob.data
    base = me.name
    old = bpy.data.meshes.get(str(ob.get(STALE_MESH_KEY, "")))
    if old is not None and old is not me and old.users <= 1:  # an older out-of-date bake: this one replaces it
        old.use_fake_user = False
        if old.users == 0:
            bpy.data.meshes.remove(old)
    me.use_fake_user = True
    me.name = f"{base} (out-of-date bake)"
    ob[STALE_MESH_KEY] = me.name
    return base


def restore_stale_mesh(ob: bpy.types.Object, base: str) -> None:
    """Undo :func:`keep_stale_mesh` (the re-mesh failed and ``ob`` keeps its mesh)."""
    ob.data.use_fake_user = False
    ob.data.name = base
    ob.pop(STALE_MESH_KEY, None)


def forget_stale(ob: bpy.types.Object) -> None:
    """A new bake (or a cleared one): drop the out-of-date mark and the kept old mesh."""
    ob.pop(STALE_KEY, None)
    name = ob.pop(STALE_MESH_KEY, None)
    old = bpy.data.meshes.get(str(name)) if name else None
    if old is not None and old is not ob.data:
        old.use_fake_user = False
        if old.users == 0:
            bpy.data.meshes.remove(old)


# ------------------------------------------------------------------------------------------ the bake job


def percent_schedule(ob: bpy.types.Object, frames: Sequence[int]) -> np.ndarray:
    """Fold percent (fraction) per frame: the keyframed ``curved_fold_mesh.fold_percent`` if animated; the set
    percent on every frame if other fold settings are keyed (as playback folds them); else a linear ramp from 0 to
    the set percent over ``frames``."""
    props = ob.curved_fold_mesh
    fc = percent_fcurve(ob)
    if fc is not None:
        return np.clip(np.array([fc.evaluate(f) for f in frames], dtype=np.float64) / 100.0, 0.0, 1.0)
    if len(frames) == 1 or any(f.data_path.startswith("curved_fold_mesh.") for f in _fcurves(ob)):
        # other settings keyed, the percent not: playback holds the percent while they change, and so does the bake
        return np.full(len(frames), props.fold_percent / 100.0)
    return np.linspace(0.0, props.fold_percent / 100.0, len(frames))


def settings_per_frame(ob: bpy.types.Object, frames: Sequence[int], settings) -> list:
    """``settings`` (a frozen copy of the solver settings, ``timeline.frozen_settings``) for each of ``frames``, with
    every keyframed one of them evaluated there: what playback folds that frame with. A bake solved every frame with
    the settings of the frame Bake was pressed on, so keyed stiffnesses played one way and baked another (a helper:
    z-extent 0.0000 baked against 0.0435 played at frame 1)."""
    keyed = {}
    for f in _fcurves(ob):
        owner, _, name = f.data_path.partition(".")
        if owner == "curved_fold_mesh" and name in vars(settings):
            keyed[name] = f
    if not keyed:
        return [settings] * len(frames)
    from types import SimpleNamespace

    out = []
    for frame in frames:
        values = dict(vars(settings))
        for name, fc in keyed.items():
            value = fc.evaluate(frame)
            values[name] = value > 0.5 if isinstance(values[name], bool) else float(value)
        out.append(SimpleNamespace(**values))
    return out


def percent_fcurve(ob: bpy.types.Object):
    """The F-curve animating ``ob``'s Fold Percent, or None."""
    return next((f for f in _fcurves(ob) if f.data_path == "curved_fold_mesh.fold_percent"), None)


def write_bake(ob: bpy.types.Object, frames: Sequence[int], positions: Sequence[np.ndarray], mesh, *, scene=None):
    """Write every frame as keyed shape keys (all or nothing), the last frame's strain/warp colours, and mark the
    bake current; returns the object."""
    from . import folding, mesh_object

    bake_shape_keys(ob, frames, positions, scene=scene)
    ob.curved_fold_mesh.baked_frames = len(frames)
    forget_stale(ob)
    strain_pct, warp_deg = folding.display_metrics(mesh, positions[-1])
    me = ob.data
    mesh_object.write_colours(me, "cf_strain", strain_pct, mesh_object.STRAIN_CLIP_PCT)
    mesh_object.write_colours(me, "cf_warp", warp_deg, mesh_object.WARP_CLIP_DEG)
    return ob


@dataclass
class BakeSummary:
    """What a bake wrote: frames, solver iterations, frames taken from the timeline cache, unconverged frames."""

    ob_name: str
    frames: list[int]
    iterations: int = 0
    cached: int = 0
    unconverged: list[int] = dc_field(default_factory=list)
    ms: float = 0.0

    def text(self) -> str:
        t = (
            f"baked {len(self.frames)} frames in {self.ms:.0f} ms ({self.iterations} solver iterations, "
            f"{self.cached} frames from the timeline cache)"
        )
        if self.unconverged:
            more = "..." if len(self.unconverged) > 5 else ""
            t += f"; not converged at frames {self.unconverged[:5]}{more}"
        return t


def bake_job(ob: bpy.types.Object, frames: Sequence[int], *, scene=None):
    """The Bake operator's one scene call: a job that folds ``ob`` frame by frame (units: solver iterations, or
    chunks of explicit steps in dynamic mode) and, when done, writes the shape keys and returns a
    :class:`BakeSummary`. Quasi-static frames come from, and go to, the timeline cache (``timeline``): a frame
    solved during playback is not solved again if it converged; each new frame warm-starts from a solved one a
    small step before it, or is solved from the natural path with the whole iteration budget
    (``timeline.FrameCache.solve_steps``)."""
    import time

    from . import folding, jobs, timeline

    jobs.stop_live(ob)  # a frame job's partial shape is not the "before" its Esc restores
    frames = [int(f) for f in frames]
    if not frames:
        raise ValueError("the frame range is empty")
    props = ob.curved_fold_mesh
    name = ob.name
    handle = jobs.ObjectHandle(ob)
    percents = percent_schedule(ob, frames)
    summary = BakeSummary(name, frames)
    dynamic = props.solver_mode == "DYNAMIC"
    cache = timeline.cache_for(ob)
    mesh = cache.mesh
    settings = folding.solver_settings(props)
    steps_per_frame = int(props.steps_per_frame)
    props = timeline.frozen_settings(props)  # the job solves with the settings of its start
    frame_settings = settings_per_frame(ob, frames, props)  # keyed ones as each frame plays them
    n = len(frames)

    def steps():
        t0 = time.perf_counter()
        positions = []
        if dynamic:
            from ..core.solve.solver import Solver

            solver = Solver(mesh, settings, "faithful")
            x, theta, v = mesh.vertices_3d.copy(), None, None
            per_frame = steps_per_frame
            for i, f in enumerate(frames):
                done = 0
                while done < per_frame:
                    k = min(per_frame - done, 50)
                    r = solver.solve(
                        float(percents[i]),
                        start=x,
                        theta_prev=theta,
                        velocities=v,
                        max_steps=k,
                        stop_on_convergence=False,
                    )
                    x, theta, v = r.positions, r.theta, r.velocities
                    done += k
                    summary.iterations += k
                    yield jobs.Progress(
                        "frame",
                        done,
                        r.residual,
                        frame=i + 1,
                        n_frames=n,
                        fraction=(i + done / per_frame) / n,
                        positions=x,
                    )
                if not np.all(np.isfinite(x)):
                    raise FloatingPointError(f"frame {f}: the solver returned non-finite positions")
                positions.append(np.asarray(x, dtype=np.float64))
        else:
            for i, f in enumerate(frames):
                now = frame_settings[i]
                hit = cache.get(f, float(percents[i]), now)
                if hit is not None and hit.converged:
                    summary.cached += 1
                    entry = hit
                else:  # playback's frames from the path are capped; a bake gives them the whole budget
                    entry = yield from cache.solve_steps(
                        f, float(percents[i]), now, frame_index=i, n_frames=n, path_budget=None
                    )
                    summary.iterations += entry.iterations
                if not entry.converged:
                    summary.unconverged.append(f)
                positions.append(entry.positions)
                yield jobs.Progress(
                    "frame",
                    entry.iterations,
                    entry.residual,
                    frame=i + 1,
                    n_frames=n,
                    fraction=(i + 1) / n,
                    positions=entry.positions,
                )
        summary.ms = 1e3 * (time.perf_counter() - t0)

        def commit():
            target = handle.require("fold object")
            write_bake(target, frames, positions, mesh, scene=scene)
            summary.ob_name = target.name  # renamed while it baked: report the name it has now
            return summary

        return commit

    return jobs.Job(name, "baking", steps(), jobs.PositionsPreview(ob, scene))
