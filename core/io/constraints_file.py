"""The pins and glue of a pattern file (``core.solve.constraints`` holds what they are and how the solver keeps
them): from ``--constraints``, the ``curved_fold:pins``/``curved_fold:glue`` fields of a FOLD file, or the
``<pattern>.constraints.json`` beside it. Read as any input file is (:func:`.reader.read_input_bytes`)."""

from __future__ import annotations

import json
from pathlib import Path

from ..pattern.model import PatternError
from ..solve.constraints import SIDECAR_SUFFIX, ConstraintSpec, parse_constraints
from .reader import read_input_bytes


def read_constraints(pattern_path: str | Path, explicit: str | Path | None = None) -> ConstraintSpec:
    """The pins and glue of a pattern file: ``explicit`` (a JSON file) if given, else the ``curved_fold:pins``/
    ``curved_fold:glue`` fields of a ``.fold`` input, else ``<pattern>.constraints.json`` beside it, else none."""
    pattern_path = Path(pattern_path)
    candidates: list[Path] = []
    if explicit is not None:
        candidates.append(Path(explicit))
    elif pattern_path.suffix.lower() == ".fold":
        candidates.append(pattern_path)
    sidecar = pattern_path.with_name(pattern_path.stem + SIDECAR_SUFFIX)
    if explicit is None and sidecar.exists():
        candidates.append(sidecar)
    for path in candidates:
        # an input file like the pattern: a regular file within the size limit (a constraints file of /dev/zero
        # grew to 24 GB before the kernel killed it, a named pipe hung, random bytes gave a traceback)
        raw = read_input_bytes(path, "constraints JSON")
        try:
            data = json.loads(raw.decode("utf-8-sig"))
        except UnicodeDecodeError as exc:
            raise PatternError(f"{path}: not UTF-8 text (byte {exc.start}); save the constraints as UTF-8") from None
        except json.JSONDecodeError as exc:
            raise PatternError(f"{path}: not valid JSON ({exc.msg}, line {exc.lineno})") from exc
        except RecursionError:
            raise PatternError(f"{path}: JSON nested too deeply") from None
        spec = parse_constraints(data, str(path))
        if not spec.empty or path != pattern_path:
            return spec
    return ConstraintSpec()
