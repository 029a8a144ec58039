"""Size limits on input files, so a hostile or broken file ends in one clear message instead of a hang or a
MemoryError.

Each limit is far above any real crease pattern (the biggest vendored fixture, CircularPleat-antiFacet, is a
0.2 MB SVG of ~2,000 elements that discretises to ~11,000 segments) and can be raised with an environment variable;
the message names the limit, the value met and that variable.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from ..pattern.model import PatternError


@dataclass(frozen=True)
class Limit:
    """One limit: its default value, the environment variable that overrides it and what it counts."""

    default: int
    variable: str
    what: str

    @property
    def value(self) -> int:
        """The limit in force (the environment variable when it is a positive integer, else the default)."""
        raw = os.environ.get(self.variable, "").strip()
        try:
            value = int(raw)
        except ValueError:
            return self.default
        return value if value > 0 else self.default

    def check(self, count: int, where: str) -> None:
        """Raise :class:`PatternError` when ``count`` is above the limit."""
        limit = self.value
        if count > limit:
            raise PatternError(
                f"{where}: {self.what} {count:,} is above the limit of {limit:,} "
                f"(set the environment variable {self.variable} to raise it)"
            )


FILE_MB = Limit(32, "CURVED_FOLD_MAX_FILE_MB", "file size (MB)")
"""Largest input file (SVG, FOLD), in MB: about 3 s of JSON parsing on the shared 2-core machine, and room for a
FOLD file of 200,000 vertices and edges written at full precision."""

SVG_ELEMENTS = Limit(50_000, "CURVED_FOLD_MAX_ELEMENTS", "number of SVG elements")
"""Most XML elements in one SVG file."""

PATH_SEGMENTS = Limit(200_000, "CURVED_FOLD_MAX_PATH_SEGMENTS", "number of drawn path segments")
"""Most drawn segments (path commands, polyline points, shapes' sides) in one SVG file; each becomes at least one
crease segment, and the discretisation keeps at most ``MAX_SEGMENTS`` (200,000) anyway."""

FOLD_ENTRIES = Limit(200_000, "CURVED_FOLD_MAX_FOLD_ENTRIES", "array length")
"""Most entries in one FOLD array (vertices, edges, faces, frames)."""

NESTING = Limit(64, "CURVED_FOLD_MAX_NESTING", "nesting depth")
"""Deepest nesting of SVG groups or of FOLD JSON arrays/objects (a real file needs 3 to 10)."""


def check_file_size(n_bytes: int, where: str) -> None:
    """Raise :class:`PatternError` when a file of ``n_bytes`` is above :data:`FILE_MB`."""
    limit = FILE_MB.value
    if n_bytes > limit * 1024 * 1024:
        raise PatternError(
            f"{where}: file size {n_bytes / 1048576:.1f} MB is above the limit of {limit} MB "
            f"(set the environment variable {FILE_MB.variable} to raise it)"
        )
