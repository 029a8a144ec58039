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
            output_target(path)
        except OSError as exc:
            raise PatternError(f"{option} {exc}") from None


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


def check_complete(path: Path, suffix: str, n_vertices: int) -> None:
    """Raise :class:`OSError` unless the file a Blender exporter wrote at ``path`` is whole.

    Blender's C++ OBJ writer ignores write errors (a full disk left an OBJ cut mid-line and the operator said
    "File exported successfully"), so the file is checked before it replaces anything: an OBJ must end with a
    newline and hold ``n_vertices`` ``v`` lines; a GLB's header length must equal the file size; a .blend file
    must end with its ``ENDB`` block.
    """
    suffix = suffix.lower()
    size = path.stat().st_size
    if suffix == ".obj":
        with open(path, "rb") as fh:
            data = fh.read()
        count = data.count(b"\nv ") + data.startswith(b"v ")
        if not data.endswith(b"\n") or count != n_vertices:
            raise OSError(f"the OBJ file is incomplete ({count} of {n_vertices} vertices, {size} bytes written)")
    elif suffix == ".glb":
        with open(path, "rb") as fh:
            head = fh.read(12)
        declared = int.from_bytes(head[8:12], "little") if len(head) == 12 and head[:4] == b"glTF" else -1
        if declared != size:
            raise OSError(f"the GLB file is incomplete ({size} of {declared} bytes written)")
    elif suffix == ".blend":
        with open(path, "rb") as fh:
            fh.seek(max(size - 64, 0))
            tail = fh.read()
        if b"ENDB" not in tail:
            raise OSError(f"the .blend file is incomplete (no end block; {size} bytes written)")
