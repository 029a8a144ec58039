"""The 3D viewport sidebar panel and menu entries; drawing only, no numerics."""

from __future__ import annotations

import sys


def register() -> None:
    from ..registration import register_package

    register_package(sys.modules[__name__])


def unregister() -> None:
    from ..registration import unregister_package

    unregister_package(sys.modules[__name__])
