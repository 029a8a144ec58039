"""Atomic file writing: a half-written output file must never replace a good one.

Data is written to a temporary file in the destination's own folder (so the final rename stays on one file system),
flushed and fsynced, then moved over the destination with :func:`os.replace`, which is atomic on POSIX and Windows.
If anything fails the temporary file is removed and the destination is left untouched. The file gets the mode a plain
``open(path, "w")`` would give it (an existing file keeps its mode; a new one 0o666 less the umask), not the private
0o600 of a temporary file.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def _final_mode(dest: Path) -> int:
    """The permission bits ``dest`` would have if written in place."""
    try:
        return dest.stat().st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


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
        os.chmod(tmp_name, _final_mode(dest))
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
