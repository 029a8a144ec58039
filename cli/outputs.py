"""Checks on the command line's output files before any work starts, and a report JSON without ``Infinity``.

* :func:`check_outputs` refuses an output that is the input (``--out pattern.fold`` on ``pattern.fold`` would
  replace the pattern with its fold), two outputs that are one file (``--report`` equal to ``--out`` would replace
  the mesh by the report), and targets that cannot be written (devices, FIFOs, folders, a missing folder), naming
  the options and the user's paths. Symlinks count as the files they point to.
* :func:`finite_json` turns every non-finite float into ``null``: ``json.dumps`` would otherwise write ``NaN`` or
  ``Infinity``, which is not JSON.
"""

from __future__ import annotations

import math
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

from ..core.io.atomic import output_target, same_file
from ..core.pattern.model import PatternError


def check_outputs(input_path: str | Path, outputs: dict[str, str | Path | None]) -> None:
    """Raise :class:`PatternError` unless every output (option name → path, None = not asked) can be written and
    is neither the input nor another output."""
    given = [(option, Path(p)) for option, p in outputs.items() if p is not None]
    for option, path in given:
        if same_file(path, input_path):
            raise PatternError(f"{option} {path}: is the input file {input_path}; choose another output file")
    for i, (opt_a, a) in enumerate(given):
        for opt_b, b in given[i + 1 :]:
            if same_file(a, b):
                raise PatternError(f"{opt_a} {a} and {opt_b} {b} name the same file; give each its own file")
    for option, path in given:
        try:
            target = output_target(path)
        except OSError as exc:
            raise PatternError(f"{option} {exc}") from None
        _probe_folder(option, path, target.parent)


def _probe_folder(option: str, path: Path, folder: Path) -> None:
    """Raise :class:`PatternError` unless a file can be made in ``folder`` (a temporary one, removed at once): a
    read-only file system or folder was found only when the result was written, after the whole fold (seconds on
    a big pattern), and the message did not name the option."""
    try:
        fd, name = tempfile.mkstemp(prefix=".curved_fold-probe.", dir=folder)
    except OSError as exc:
        raise PatternError(f"{option} {path}: cannot write in {folder}: {exc.strerror or exc}") from None
    os.close(fd)
    os.unlink(name)


def stdout_to_devnull() -> None:
    """Point standard output at /dev/null: its reader went away (`| head -1`), and the flush at exit (or a later
    print) would raise BrokenPipeError again."""
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, sys.stdout.fileno())
    os.close(null)


def finite_json(value: Any) -> Any:
    """``value`` with every NaN or infinite float (also inside lists and dicts) replaced by ``None``."""
    if type(value).__module__ == "numpy" and hasattr(value, "tolist"):
        value = value.tolist()  # numpy scalar or array → Python numbers and lists
    if isinstance(value, dict):
        return {k: finite_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_json(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
