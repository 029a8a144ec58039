"""The third front door: ``blender -c curved_fold <subcommand> ...`` runs the same command line as
``python -m curved_fold`` (see :mod:`.`), inside Blender, with the add-on enabled.

Registered with ``bpy.utils.register_cli_command`` when the extension is enabled (:func:`register`, called by
the add-on's ``register``), unregistered when disabled.
"""

from __future__ import annotations

import bpy

COMMAND_ID = "curved_fold"

_handle = None
"""Opaque handle returned by ``register_cli_command`` (``None`` while not registered)."""


def run_cli_command(argv: list[str]) -> int:
    """Callback of ``blender -c curved_fold``: run :func:`.main` on the arguments after the command id."""
    from . import main

    try:
        return int(main(list(argv)) or 0)
    except SystemExit as exc:  # argparse exits on --help and usage errors; Blender expects a return code
        return exc.code if isinstance(exc.code, int) else 1


def is_registered() -> bool:
    """True while ``blender -c curved_fold`` is registered by this module."""
    return _handle is not None


def register() -> None:
    global _handle
    if _handle is None and hasattr(bpy.utils, "register_cli_command"):
        _handle = bpy.utils.register_cli_command(COMMAND_ID, run_cli_command)


def unregister() -> None:
    global _handle
    if _handle is not None:
        bpy.utils.unregister_cli_command(_handle)
        _handle = None
