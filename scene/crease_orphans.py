"""Crease-display curves go with their fold object: deleting the folded mesh deletes its red/blue crease curves.

A fold object's mountain and valley curves (``mesh_object._write_crease_curves``) are child objects that cannot be
selected (a click on the sheet must select the sheet). Blender keeps the children of a deleted object, unparented:
after Object ▸ Delete on a folded mesh its crease curves stayed in the viewport, folded in mid-air, and could not be
clicked to delete them. When a depsgraph update changed collections (a deletion does) and crease-display curves are
left without a parent, their removal is scheduled on a timer (:func:`remove_orphaned_crease_curves`, with their curve
data if nothing else uses it). Not in the handler itself: removing objects there freed IDs that the same update's
list still named, and the next handler read a freed entry. Undo brings the mesh and its curves back together.
"""

from __future__ import annotations

import bpy
from bpy.app.handlers import persistent

from . import app_handlers


def orphaned_crease_curves() -> list[bpy.types.Object]:
    """Crease-display curves (``cf_crease_role``) whose fold object is gone (no parent)."""
    return [ob for ob in bpy.data.objects if ob.type == "CURVE" and ob.parent is None and "cf_crease_role" in ob]


def remove_orphaned_crease_curves() -> int:
    """Remove :func:`orphaned_crease_curves` (and curve data left unused); returns how many were removed."""
    gone = orphaned_crease_curves()
    for ob in gone:
        data = ob.data
        bpy.data.objects.remove(ob)
        if data is not None and data.users == 0:
            bpy.data.curves.remove(data)
    return len(gone)


def _removal() -> None:
    """The timer's call (returns ``None``: it runs once)."""
    remove_orphaned_crease_curves()


@persistent
def on_depsgraph_update(scene, depsgraph) -> None:
    """After a change of collections (objects deleted or unlinked), schedule the removal of crease curves left
    without their sheet (once, right after this update)."""
    if depsgraph.id_type_updated("COLLECTION") and not bpy.app.timers.is_registered(_removal):
        if orphaned_crease_curves():
            bpy.app.timers.register(_removal, first_interval=0.0)


def register_extra() -> None:
    app_handlers.attach(bpy.app.handlers.depsgraph_update_post, on_depsgraph_update)


def unregister_extra() -> None:
    app_handlers.detach(bpy.app.handlers.depsgraph_update_post, on_depsgraph_update)
    if bpy.app.timers.is_registered(_removal):
        bpy.app.timers.unregister(_removal)
