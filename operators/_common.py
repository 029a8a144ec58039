"""What the operators share: the poll for operators that act on a folded mesh."""

from __future__ import annotations


def poll_fold_object(cls, context, *, object_mode: bool = True) -> bool:
    """Operator poll: the active object is a folded mesh (and, with ``object_mode``, Blender is in Object Mode)."""
    ob = context.active_object
    if ob is None or not ob.curved_fold_mesh.is_fold_mesh:
        cls.poll_message_set("The active object is not a folded mesh (use Fold Crease Pattern first)")
        return False
    return context.mode == "OBJECT" or not object_mode
