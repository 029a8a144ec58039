"""What the operators share: the poll for operators that act on a folded mesh, and Object Mode for a reader."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import bpy


def poll_fold_object(cls, context, *, object_mode: bool = True) -> bool:
    """Operator poll: the active object is a folded mesh (and, with ``object_mode``, Blender is in Object Mode)."""
    ob = context.active_object
    if ob is None or not ob.curved_fold_mesh.is_fold_mesh:
        cls.poll_message_set("The active object is not a folded mesh (use Fold Crease Pattern first)")
        return False
    return context.mode == "OBJECT" or not object_mode


@contextlib.contextmanager
def object_mode(context) -> Iterator[None]:
    """Run the body in Object Mode, back in Edit Mode after it if the active object was being edited. In Edit Mode a
    mesh's arrays are empty: Export Mesh and Export SVG, which Edit Mode allows, ended in a Python traceback (a
    designer session). glTF-Blender-IO's exporter does the same round trip; the edit mesh is written back, as Tab
    writes it."""
    ob = context.active_object
    edited = ob is not None and ob.mode == "EDIT"
    if edited:
        bpy.ops.object.mode_set(mode="OBJECT")
    try:
        yield
    finally:
        if edited and context.active_object is ob:
            bpy.ops.object.mode_set(mode="EDIT")
