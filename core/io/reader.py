"""Read a crease pattern from any supported file: SVG, FOLD or a .blend file's crease curves.

:func:`read_pattern` dispatches on the suffix and always returns a discretised :class:`~.pattern.CreasePattern`;
:func:`read_curves` returns :class:`~.pattern.CreaseCurve` objects (exact curves; polylines for FOLD) for the Import
operator, which turns them into Blender curves. Reading a .blend file needs Blender's ``bpy``: the Blender layer
registers its reader (``scene.curves.read_blend_file``) with :func:`register_blend_reader`, so the engine never imports
``bpy`` or the layers above it.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Callable, Generator
from pathlib import Path

from .. import run_to_end
from ..pattern.discretize import discretize
from ..pattern.model import CreaseCurve, CreasePattern, PatternError
from . import limits

SUFFIXES = (".svg", ".fold", ".blend")


_blend_reader: list[Callable[..., tuple[list[CreaseCurve], list[str]]]] = []
"""The registered .blend reader (at most one), see :func:`register_blend_reader`."""


def register_blend_reader(reader: Callable[..., tuple[list[CreaseCurve], list[str]]]) -> None:
    """Let :func:`read_curves` open .blend files with ``reader`` (``(path, collection=None)`` → crease curves and
    warnings); Blender's layer calls this."""
    _blend_reader[:] = [reader]


def _blend_curves(path: Path, collection: str | None = None) -> tuple[list[CreaseCurve], list[str]]:
    if not _blend_reader:
        raise PatternError(f"{path.name}: reading .blend files needs Blender (bpy), which is not available here")
    curves, warnings = _blend_reader[0](str(path), collection=collection)
    if not curves:
        raise PatternError(f"{path.name}: no crease curves found in the .blend file")
    return curves, warnings


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise PatternError(
            f"{path.name}: unknown file type {path.suffix or '(no suffix)'!r}; expected one of {', '.join(SUFFIXES)}"
        )
    st = _check_regular(path)
    if suffix != ".blend":  # a .blend file is opened by Blender, which reads only what it needs
        limits.check_file_size(st.st_size, str(path))
    return suffix


def _check_regular(path: Path) -> os.stat_result:
    """The file's status; a missing file, a folder, FIFO or device raises :class:`PatternError` (a FIFO would
    block the reader forever, a device could be endless)."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise PatternError(f"{path}: no such file") from None
    except OSError as exc:
        raise PatternError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if not stat.S_ISREG(st.st_mode):
        kind = (
            "a folder"
            if stat.S_ISDIR(st.st_mode)
            else "a FIFO (named pipe)"
            if stat.S_ISFIFO(st.st_mode)
            else "a device or socket"
        )
        raise PatternError(f"{path}: is {kind}, not a regular file")
    return st


GZIP_MAGIC = b"\x1f\x8b"
ZIP_MAGIC = b"PK\x03\x04"


def read_input_bytes(path: str | os.PathLike[str], kind: str) -> bytes:
    """The bytes of an input file of type ``kind`` (``"SVG"``, ``"FOLD"``), checked first: a regular file, not
    above :data:`.limits.FILE_MB`, not compressed (``.svgz`` or a gzip/zip archive gets a message saying so)."""
    p = Path(path)
    if not p.exists():
        raise PatternError(f"{p}: cannot read {kind} file: no such file")
    st = _check_regular(p)
    limits.check_file_size(st.st_size, str(p))
    try:
        with open(p, "rb") as fh:
            data = fh.read(limits.FILE_MB.value * 1024 * 1024 + 1)  # the file may have grown since stat
    except OSError as exc:
        raise PatternError(f"{p}: cannot read {kind} file: {exc.strerror or exc}") from None
    limits.check_file_size(len(data), str(p))
    if data.startswith(GZIP_MAGIC):
        raise PatternError(f"{p.name}: gzip-compressed data, not a plain {kind} file; decompress it first (gunzip)")
    if data.startswith(ZIP_MAGIC):
        raise PatternError(f"{p.name}: a zip archive, not a plain {kind} file; extract it first")
    return data


def read_curves(path: str | os.PathLike[str], *, collection: str | None = None) -> tuple[list[CreaseCurve], list[str]]:
    """The crease curves of a file and the warnings met reading them: exact curves from .svg and .blend, polylines
    (segments chained through vertices where two meet, ``core.pattern.polylines``) from .fold. ``collection``: of a
    .blend file, the curves of that collection only (else those of its scene)."""
    return run_to_end(read_curves_steps(path, collection=collection))


def read_curves_steps(
    path: str | os.PathLike[str], *, collection: str | None = None
) -> Generator[str, None, tuple[list[CreaseCurve], list[str]]]:
    """:func:`read_curves` in units of work: an SVG's elements a few hundred at a time (a Blender import runs them
    in a job's slices), another file in one."""
    p = Path(path)
    suffix = _suffix(p)
    if collection is not None and suffix != ".blend":
        raise PatternError(f"{p.name}: only a .blend file has collections to choose from ('{collection}')")
    if suffix == ".svg":
        from .svg import read_svg_steps

        drawing = yield from read_svg_steps(p)
        return drawing.curves, list(drawing.warnings)
    if suffix == ".blend":
        return _blend_curves(p, collection)
    from ..pattern.polylines import curves_from_pattern
    from .fold import read_fold_pattern

    pattern = read_fold_pattern(p)
    return curves_from_pattern(pattern), list(pattern.warnings)


def read_pattern(
    path: str | os.PathLike[str],
    *,
    interval: float | None = None,
    tolerance: float | None = None,
    merge_tolerance: float | None = None,
    collection: str | None = None,
) -> CreasePattern:
    """Read and discretise a crease pattern (.svg, .blend) or read a discretised one (.fold).

    Discretisation parameters are in mm; ``None`` means the scale-aware defaults (see ``core.pattern.discretize``).
    Another tool's FOLD file is already straight segments: the interval and tolerance thin its dense polylines and
    split its border (:func:`.fold.pattern_for_folding`); our own FOLD files read back as written, and the merge
    tolerance does not apply to FOLD files. Warnings from reading come first in the pattern's ``warnings``.
    ``collection``: see :func:`read_curves`.
    """
    p = Path(path)
    suffix = _suffix(p)
    if suffix == ".fold" and collection is None:
        from .fold import read_fold_pattern

        return read_fold_pattern(p, interval=interval, tolerance=tolerance)
    curves, warnings = read_curves(p, collection=collection)
    pattern = discretize(curves, interval=interval, tolerance=tolerance, merge_tolerance=merge_tolerance)
    pattern.warnings = warnings + pattern.warnings
    return pattern
