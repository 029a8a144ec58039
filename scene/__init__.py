"""Bridge between Blender data and the engine: curve objects in, mesh objects, shape keys and files out.

This is the only place (with ``operators`` and ``panels``) that touches ``bpy`` data; :mod:`..core` never does.
"""

from __future__ import annotations

import sys


def register() -> None:
    from ..registration import register_package

    register_package(sys.modules[__name__])


def unregister() -> None:
    from ..registration import unregister_package

    unregister_package(sys.modules[__name__])
