"""Curved Fold: fold curved-crease patterns drawn as Bézier curves, inside Blender.

The repository root is the add-on package (``curved_fold``; as an extension ``bl_ext.<repo>.curved_fold``).
Importing it does not import ``bpy``: the engine in :mod:`.core` runs anywhere numpy does, and Blender's classes
are loaded only by :func:`register`.
"""


def register() -> None:
    """Register properties, operators and panels (called by Blender when the extension is enabled)."""
    from . import operators, panels, scene

    scene.register()
    operators.register()
    panels.register()


def unregister() -> None:
    """Unregister everything :func:`register` added, in reverse order."""
    from . import operators, panels, scene

    panels.unregister()
    operators.unregister()
    scene.unregister()
