"""The Curved Fold engine: crease patterns, discretisation, ruling-aware meshing, solver, metrics, file formats.

Everything here takes and returns plain data (numpy arrays, small dataclasses) and never touches a Blender scene
or ``bpy.context``; only the edge swaps use ``bmesh`` (as the design card asks). See ``docs/architecture.md``.
"""

import sys
from collections.abc import Generator
from typing import TypeVar

_R = TypeVar("_R")


def run_to_end(steps: Generator[object, None, _R]) -> _R:
    """Run a generator of units of work to its end and return its value.

    The engine's long stages come in units (``discretize_steps``, ``Solver.solve_steps``, ``newton_steps``) so a
    Blender job can run one per slice; the command line and the plain functions run them through here."""
    while True:
        try:
            next(steps)
        except StopIteration as done:
            return done.value


def as_units(steps: Generator[object, None, _R], label: object) -> Generator[object, None, _R]:
    """Run ``steps`` (a stage in units of work) yielding ``label`` after each of its units; return its value.

    For a stage nested in another whose units are labelled differently (``Solver.prepare_steps`` runs the nested
    dissection's units as "ordering"; a Blender job labels each with its progress)."""
    while True:
        try:
            next(steps)
        except StopIteration as done:
            return done.value
        yield label


def load_bpy() -> None:
    """Import Blender's ``bpy`` module (``bmesh`` and ``mathutils`` need it first) with SIGINT and SIGTERM held
    until it is loaded (:func:`.io.atomic.signals_held`): ~0.35 s of Blender set-up that must not be cut."""
    if "bpy" in sys.modules:
        return
    from .io.atomic import signals_held

    with signals_held():
        import bpy  # noqa: F401
