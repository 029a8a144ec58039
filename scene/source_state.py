"""Whether a fold object's source curves changed since its mesh was built from them (the sidebar's notice).

With Live off nothing re-folds by itself, so after a curve edit the folded mesh — and any bake, which folds that
stored mesh — no longer matches its curves. Fold and every rebuild from the curves store a *fingerprint* of the
sources on the fold object (:data:`FINGERPRINT_KEY`, an ID property: it is saved in the .blend file and restored by
undo): a hash of each source curve's control points and handles, spline types and cyclic flags, world matrix, role
and fold angle (not of the scene's unit scale, :data:`VERSION`). :func:`sources_changed` compares it with the
curves as they are now.

It runs lazily, when the panel is drawn, and only after something that can change the answer: the result is cached
per fold object until a depsgraph update touches a curve object or a collection (:func:`on_depsgraph_update` only
clears the cache), an undo, redo or file load, or the object's stored fingerprint or sources change. Playback and
edits of meshes do not invalidate it. A fold object made before fingerprints existed has none and shows no notice.
"""

from __future__ import annotations

import hashlib

import bpy
import numpy as np
from bpy.app.handlers import persistent

from . import app_handlers

FINGERPRINT_KEY = "cf_sources_fingerprint"
"""Object ID property of a fold object: fingerprint (hex) of the source curves its mesh was last built from."""

_cache: dict[str, tuple[tuple, bool]] = {}
"""Fold object name → (what the answer depends on, whether its sources changed)."""


def _curve_digest(ob: bpy.types.Object) -> bytes:
    """Hash of what folding reads from one crease curve object: role, signed angle, world matrix, splines."""
    h = hashlib.blake2b(digest_size=16)
    props = ob.curved_fold
    h.update(f"{props.role}|{props.signed_fold_angle!r}".encode())
    h.update(np.array(ob.matrix_world, dtype=np.float64).tobytes())
    for spline in ob.data.splines:
        bezier = spline.type == "BEZIER"
        points = spline.bezier_points if bezier else spline.points
        h.update(f"|{spline.type}|{spline.use_cyclic_u}|{len(points)}|".encode())
        for attr, width in (("co", 3), ("handle_left", 3), ("handle_right", 3)) if bezier else (("co", 4),):
            values = np.empty(width * len(points), dtype=np.float32)
            points.foreach_get(attr, values)
            h.update(values.tobytes())
    return h.digest()


VERSION = "2:"
"""Prefix of a fingerprint without the scene's unit scale. The first ones (no prefix) hashed it too, so switching
Unit Scale said "source curves changed" although the fold does not change with it (the curves and the folded mesh
keep their size in Blender units, ``mesh_object.flat_rescale``); they are still compared as they were made."""


def fingerprint(sources, scene: bpy.types.Scene | None = None, *, with_unit_scale: bool = False) -> str:
    """Fingerprint of the crease curve objects ``sources`` as they are now, independent of their order and names
    (renaming a curve does not change the fold): :data:`VERSION` and a hex digest, or the first kind's digest alone
    (``with_unit_scale``: the scene's unit scale hashed in)."""
    h = hashlib.blake2b(digest_size=16)
    if with_unit_scale:
        scene = scene or bpy.context.scene
        h.update(repr(float(scene.unit_settings.scale_length) if scene is not None else 1.0).encode())
    for digest in sorted(_curve_digest(ob) for ob in sources):
        h.update(digest)
    return h.hexdigest() if with_unit_scale else VERSION + h.hexdigest()


def record(ob: bpy.types.Object, value: str | None) -> None:
    """Store ``value`` (a :func:`fingerprint` taken when the mesh was built) on the fold object ``ob``."""
    if value is not None:
        ob[FINGERPRINT_KEY] = value


def sources_changed(ob: bpy.types.Object, scene: bpy.types.Scene | None = None) -> bool:
    """Whether the source curves of the fold object ``ob`` changed (geometry, transform, role, fold angle, which
    curves) since its mesh was last built from them. False when nothing was recorded or no source is left (Re-fold
    then only re-solves the stored mesh). Cached until a curve or collection is updated (see the module)."""
    stored = ob.get(FINGERPRINT_KEY)
    if not stored:
        return False
    from .folding import source_objects  # lazy: folding records fingerprints through this module

    scene = scene or bpy.context.scene
    props = ob.curved_fold_mesh
    coll = props.source_collection
    key = (
        str(stored),
        float(scene.unit_settings.scale_length) if scene is not None else 1.0,
        coll.name if coll is not None else None,
        tuple(s.object.name if s.object is not None else "" for s in props.sources),
    )
    hit = _cache.get(ob.name)
    if hit is not None and hit[0] == key:
        return hit[1]
    sources = source_objects(ob)
    now = fingerprint(sources, scene, with_unit_scale=not str(stored).startswith(VERSION))
    changed = bool(sources) and now != stored
    _cache[ob.name] = (key, changed)
    return changed


def invalidate() -> None:
    """Forget every cached answer (a curve or collection changed, or undo, redo, file load)."""
    _cache.clear()


def _touches_sources(id_) -> bool:
    """An updated datablock that can change some fold object's sources: a curve object that is not one of a fold
    object's own crease-display curves, or a collection (curves added or removed)."""
    if isinstance(id_, bpy.types.Object):
        return id_.type == "CURVE" and "cf_crease_role" not in id_
    return isinstance(id_, bpy.types.Collection)


@persistent
def on_depsgraph_update(scene, depsgraph) -> None:
    """Drop the cached answers when a curve object or a collection was updated (no other work here)."""
    for update in depsgraph.updates:
        id_ = update.id.original if hasattr(update.id, "original") else update.id
        if _touches_sources(id_):
            invalidate()
            return


@persistent
def on_undo_redo_load(*_args) -> None:
    """Undo, redo and file loads replace the data: drop the cached answers."""
    invalidate()


_HANDLERS = (
    ("depsgraph_update_post", on_depsgraph_update),
    ("undo_post", on_undo_redo_load),
    ("redo_post", on_undo_redo_load),
    ("load_post", on_undo_redo_load),
)


def register_extra() -> None:
    for name, function in _HANDLERS:
        app_handlers.attach(getattr(bpy.app.handlers, name), function)


def unregister_extra() -> None:
    for name, function in _HANDLERS:
        app_handlers.detach(getattr(bpy.app.handlers, name), function)
    invalidate()
