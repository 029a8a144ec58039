"""Curved Fold: fold curved-crease patterns drawn as Bézier curves, inside Blender.

The repository root is the add-on package (``curved_fold``; as an extension ``bl_ext.<repo>.curved_fold``).
Importing it does not import ``bpy``: the engine in :mod:`.core` runs anywhere numpy does, and Blender's classes
are loaded only by :func:`register`.

Registration walks the Blender layers bottom-up (``scene`` → ``operators`` → ``panels``) module by module, so no
package keeps a hand-written list: each module may define ``CLASSES`` (a tuple of ``bpy.types`` classes, registered in
order) and optional ``register_extra()`` / ``unregister_extra()`` hooks for what is not a class (properties on
``bpy.types.Object``, menu entries, handlers). Modules are visited in name order, which is why property groups live
in ``scene`` (registered first). ``blender -c curved_fold`` is registered last (:mod:`.cli.blender`).
"""

from __future__ import annotations

from types import ModuleType


def _modules(package: ModuleType) -> list[ModuleType]:
    import importlib
    import pkgutil

    names = sorted(m.name for m in pkgutil.iter_modules(package.__path__) if not m.name.startswith("_"))
    return [importlib.import_module(f"{package.__name__}.{name}") for name in names]


def register_package(package: ModuleType) -> None:
    """Register the ``CLASSES`` of every module of ``package``, then call its ``register_extra()``."""
    import bpy

    for module in _modules(package):
        for cls in getattr(module, "CLASSES", ()):
            bpy.utils.register_class(cls)
        hook = getattr(module, "register_extra", None)
        if hook is not None:
            hook()


def unregister_package(package: ModuleType) -> None:
    """Undo :func:`register_package`, in reverse order."""
    import bpy

    for module in reversed(_modules(package)):
        hook = getattr(module, "unregister_extra", None)
        if hook is not None:
            hook()
        for cls in reversed(getattr(module, "CLASSES", ())):
            if getattr(cls, "is_registered", False):
                bpy.utils.unregister_class(cls)


def register() -> None:
    """Register properties, operators, panels and ``blender -c curved_fold`` (Blender calls this on enable)."""
    from . import operators, panels, scene
    from .cli import blender

    for package in (scene, operators, panels):
        register_package(package)
    blender.register()


def unregister() -> None:
    """Unregister everything :func:`register` added, in reverse order."""
    from . import operators, panels, scene
    from .cli import blender

    blender.unregister()
    for package in (panels, operators, scene):
        unregister_package(package)
