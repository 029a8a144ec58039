"""Registration of Blender classes, module by module, so that no package keeps a hand-written list.

Each module of ``scene``, ``operators`` and ``panels`` may define ``CLASSES`` (a tuple of ``bpy.types`` classes,
registered in order) and optional ``register_extra()`` / ``unregister_extra()`` hooks for what is not a class
(properties on ``bpy.types.Object``, menu entries, handlers). Modules are visited in name order, which is why
property groups live in ``scene`` (registered first).
"""

from __future__ import annotations

import importlib
import pkgutil
from types import ModuleType


def _modules(package: ModuleType) -> list[ModuleType]:
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
