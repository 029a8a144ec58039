"""Atomic file writing: a half-written output file must never replace a good one.

Data is written to a temporary file in the destination's own folder (so the final rename stays on one file system),
flushed and fsynced, then moved over the destination with :func:`os.replace`, which is atomic on POSIX and Windows.
If anything fails the temporary file is removed and the destination is left untouched.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; returns the resolved destination path.

    Raises :class:`OSError` (e.g. the folder does not exist or is not writable) without leaving a temp file behind.
    """
    dest = Path(path)
    folder = dest.parent if str(dest.parent) else Path(".")
    fd, tmp_name = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp_name, dest)
    except BaseException:
        try:
            os.unlink(tmp_name)
        except OSError:
            pass
        raise
    return dest.resolve()


def atomic_write_text(path: str | os.PathLike[str], text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically (UTF-8 by default); returns the resolved destination path."""
    return atomic_write_bytes(path, text.encode(encoding))
