"""Operators: thin over :mod:`..core` and :mod:`..scene` — read the scene, call the engine, write results back."""

from __future__ import annotations

import sys


def register() -> None:
    from ..registration import register_package

    register_package(sys.modules[__name__])


def unregister() -> None:
    from ..registration import unregister_package

    unregister_package(sys.modules[__name__])
