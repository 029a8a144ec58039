"""Read a crease pattern from any supported file: SVG, FOLD or a .blend file's crease curves.

:func:`read_pattern` dispatches on the suffix and always returns a discretised :class:`~.pattern.CreasePattern`;
:func:`read_curves` returns :class:`~.pattern.CreaseCurve` objects (exact curves; polylines for FOLD) for the Import
operator, which turns them into Blender curves. Reading a .blend file needs Blender's ``bpy``: the Blender layer
registers its reader (``scene.curves.read_blend_file``) with :func:`register_blend_reader`, so the engine never imports
``bpy`` or the layers above it.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from ..pattern.discretize import discretize
from ..pattern.model import CreaseCurve, CreasePattern, PatternError

SUFFIXES = (".svg", ".fold", ".blend")


_blend_reader: list[Callable[[str], list[CreaseCurve]]] = []
"""The registered .blend reader (at most one), see :func:`register_blend_reader`."""


def register_blend_reader(reader: Callable[[str], list[CreaseCurve]]) -> None:
    """Let :func:`read_curves` open .blend files with ``reader`` (path → crease curves); Blender's layer calls this."""
    _blend_reader[:] = [reader]


def _blend_curves(path: Path) -> list[CreaseCurve]:
    if not _blend_reader:
        raise PatternError(f"{path.name}: reading .blend files needs Blender (bpy), which is not available here")
    curves = _blend_reader[0](str(path))
    if not curves:
        raise PatternError(f"{path.name}: no crease curves found in the .blend file")
    return curves


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise PatternError(
            f"{path.name}: unknown file type {path.suffix or '(no suffix)'!r}; expected one of {', '.join(SUFFIXES)}"
        )
    if not path.is_file():
        raise PatternError(f"{path}: no such file")
    return suffix


def read_curves(path: str | os.PathLike[str]) -> tuple[list[CreaseCurve], list[str]]:
    """The crease curves of a file and the warnings met reading them: exact curves from .svg and .blend, polylines
    (segments chained through vertices where two meet, ``core.polylines``) from .fold."""
    p = Path(path)
    suffix = _suffix(p)
    if suffix == ".svg":
        from .svg import read_svg

        drawing = read_svg(p)
        return drawing.curves, list(drawing.warnings)
    if suffix == ".blend":
        return _blend_curves(p), []
    from ..pattern.polylines import curves_from_pattern
    from .fold import fold_to_pattern, read_fold

    pattern = fold_to_pattern(read_fold(p))
    return curves_from_pattern(pattern), list(pattern.warnings)


def read_pattern(
    path: str | os.PathLike[str],
    *,
    interval: float | None = None,
    tolerance: float | None = None,
    merge_tolerance: float | None = None,
) -> CreasePattern:
    """Read and discretise a crease pattern (.svg, .blend) or read a discretised one (.fold).

    Discretisation parameters are in mm; ``None`` means the scale-aware defaults (see ``core.discretize``).
    They are ignored for FOLD files, which are already straight segments. Warnings from reading come first in
    the pattern's ``warnings``.
    """
    p = Path(path)
    suffix = _suffix(p)
    if suffix == ".fold":
        from .fold import fold_to_pattern, read_fold

        return fold_to_pattern(read_fold(p))
    curves, warnings = read_curves(p)
    pattern = discretize(curves, interval=interval, tolerance=tolerance, merge_tolerance=merge_tolerance)
    pattern.warnings = warnings + pattern.warnings
    return pattern
