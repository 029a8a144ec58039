"""Adding and removing the add-on's functions in ``bpy.app.handlers`` lists, once each.

Registration can run twice (a reload, a test that registers the add-on again), and a handler appended twice runs
twice; removal must not fail when a handler is already gone. The live, pins and timeline modules use these.
"""

from __future__ import annotations

from collections.abc import Callable


def attach(handlers: list, function: Callable) -> None:
    """Append ``function`` to the handler list ``handlers`` unless it is there already."""
    if function not in handlers:
        handlers.append(function)


def detach(handlers: list, function: Callable) -> None:
    """Remove ``function`` from the handler list ``handlers`` if it is there."""
    if function in handlers:
        handlers.remove(function)
