"""Atomic file writing: a half-written output file must never replace a good one.

Data is written to a temporary file in the destination's own folder (so the final rename stays on one file system),
flushed and fsynced, then moved over the destination with :func:`os.replace`, which is atomic on POSIX and Windows.
If anything fails the temporary file is removed and the destination is left untouched, byte for byte.

* :func:`atomic_output` is the general form, for writers that insist on a path of their own (Blender's exporters):
  it yields a temporary path with the destination's suffix, and moves it into place when the block ends cleanly.
* :func:`atomic_write_bytes` / :func:`atomic_write_text` write data held in memory.
* :func:`output_target` says what a write to a path would replace: a symlink is written *through* (its final target
  is replaced, the link stays a link); a device, FIFO, socket or folder is refused (``--out /dev/sda`` must not turn
  a disk node into a regular file, nor a FIFO hang the command line).
* Temporary files alive at any moment are listed in a registry; :func:`install_signal_cleanup` makes SIGINT and
  SIGTERM remove them before the process stops; those of a process killed outright (SIGKILL) are removed by the
  next write to the same file (:func:`sweep_orphans`).

The file gets the mode a plain ``open(path, "w")`` would give it (an existing file keeps its mode; a new one 0o666
less the umask), not the private 0o600 of a temporary file. Error messages name the user's path, never the
temporary one.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import stat
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

_live_temporaries: set[str] = set()
"""Temporary files being written right now (removed by the signal handlers of :func:`install_signal_cleanup`)."""

_registry_lock = threading.Lock()


class OutputError(OSError):
    """A write that was refused or failed; the message names the user's path (``str(exc)`` is one line)."""

    def __init__(self, message: str, errno: int | None = None) -> None:
        super().__init__(message)
        self.errno = errno  # type: ignore[misc]


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def output_target(path: str | os.PathLike[str]) -> Path:
    """The file a write to ``path`` replaces: symlinks resolved to their final target (even a dangling one, which is
    then created); raises :class:`OutputError` for a device, FIFO, socket or folder, or a missing folder."""
    user = Path(path)
    target = Path(os.path.realpath(user))
    try:
        st = os.stat(target)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise OutputError(f"{user}: cannot write: {exc.strerror or exc}", exc.errno) from None
    if st is not None and not stat.S_ISREG(st.st_mode):
        via = f" (the symlink points to {target})" if target != user.absolute() else ""
        raise OutputError(f"{user}: is {_kind(st.st_mode)}{via}, not a regular file; refusing to write there")
    if not target.parent.is_dir():
        raise OutputError(f"{user}: cannot write: the folder {target.parent} does not exist")
    return target


def same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """True when paths ``a`` and ``b`` name one file (through symlinks, ``..``, or hard links)."""
    ra, rb = os.path.realpath(a), os.path.realpath(b)
    if ra == rb:
        return True
    try:
        return os.path.samefile(ra, rb)
    except OSError:
        return False


def _final_mode(dest: Path) -> int:
    """The permission bits ``dest`` would have if written in place."""
    try:
        return dest.stat().st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def _fsync_folder(folder: Path) -> None:
    """Make the rename durable (POSIX; a no-op where folders cannot be opened)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _remove(name: str) -> None:
    with contextlib.suppress(OSError):
        os.unlink(name)
    with _registry_lock:
        _live_temporaries.discard(name)


def _name_user_path(exc: BaseException, tmp: str, user: Path) -> None:
    """Rewrite an exception's message in place so it names ``user`` instead of the temporary file ``tmp``, or names
    ``user`` where it named no file (a full disk during a write: the report's message named neither the option nor
    the path; a CLI review session)."""
    if isinstance(exc, OSError) and exc.filename in (tmp, None) and exc.errno is not None:
        exc.filename = str(user)  # a failed write() names no file ("[Errno 28] No space left on device")
    exc.args = tuple(a.replace(tmp, str(user)) if isinstance(a, str) else a for a in exc.args)


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike[str], *, allow_empty: bool = False) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (same suffix, so exporters pick the same format); when the block ends
    without an exception the file written there is fsynced and moved over ``path`` (through symlinks).

    If the block raises, or nothing was written (an empty file, unless ``allow_empty``: an exporter that silently
    wrote nothing), the temporary file is removed and ``path`` keeps its old bytes.
    Exceptions leave with their messages naming ``path``, not the temporary file. Nest two of these to write a
    pair of files all-or-nothing: the inner one is moved into place first, and a failure there also discards the
    outer one.
    """
    user = Path(path)
    dest = output_target(user)
    sweep_orphans(dest)
    try:
        fd, tmp = tempfile.mkstemp(
            prefix=f".{dest.stem}.cf{os.getpid()}-", suffix=f".tmp{dest.suffix}", dir=dest.parent
        )
    except OSError as exc:
        raise OutputError(f"{user}: cannot write: {exc.strerror or exc}", exc.errno) from None
    os.close(fd)
    with _registry_lock:
        _live_temporaries.add(tmp)
    try:
        try:
            yield Path(tmp)
        except BaseException as exc:
            _name_user_path(exc, tmp, user)
            raise
        try:
            size = os.path.getsize(tmp)
        except OSError:
            size = -1
        if size < 0 or (size == 0 and not allow_empty):
            raise OutputError(f"{user}: the writer produced no data; the old file (if any) is kept")
        try:
            with open(tmp, "rb+") as fh:
                os.fsync(fh.fileno())
            os.chmod(tmp, _final_mode(dest))
            os.replace(tmp, dest)
        except OSError as exc:
            raise OutputError(f"{user}: cannot write: {exc.strerror or exc}", exc.errno) from None
        _fsync_folder(dest.parent)
    finally:
        _remove(tmp)


def sweep_orphans(dest: Path) -> list[str]:
    """Remove the temporary files of earlier writes to ``dest`` whose process is gone (POSIX); returns their names.

    A temporary file names its writer's process (``.NAME.cf<pid>-xxxx.tmp.glb``; Blender's exporters write one of
    their own inside it, ``..NAME.cf<pid>-xxxx.tmp.cf<pid>-yyyy.tmp.glb``). The signal handlers remove them on
    SIGINT and SIGTERM, but a process killed outright (SIGKILL, a power cut) cannot: they were left in the user's
    folder for good. The next write to the same file removes those whose every named process is no longer
    running; a write still in progress in another process is left alone."""
    if os.name != "posix":  # os.kill(pid, 0) is a liveness test only on POSIX
        return []
    pattern = re.compile(r"^\.{1,2}" + re.escape(dest.stem) + r"\.cf\d+-.*\.tmp" + re.escape(dest.suffix) + "$")
    removed = []
    try:
        names = [n for n in os.listdir(dest.parent) if pattern.match(n)]
    except OSError:
        return removed
    for name in names:
        if not any(_alive(int(pid)) for pid in re.findall(r"\.cf(\d+)-", name)):
            with contextlib.suppress(OSError):
                os.unlink(dest.parent / name)
                removed.append(name)
    return removed


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists (POSIX; a process of another user counts as alive)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; returns the resolved destination path.

    Raises :class:`OutputError` (an :class:`OSError`: the folder does not exist or is not writable, the disk is
    full, the target is a device) naming ``path``, without leaving a temporary file behind.
    """
    with atomic_output(path, allow_empty=True) as tmp:
        try:
            with open(tmp, "wb") as fh:
                fh.write(data)
                fh.flush()
        except OSError as exc:
            raise OutputError(f"{path}: cannot write: {exc.strerror or exc}", exc.errno) from None
    return output_target(path)


def atomic_write_text(path: str | os.PathLike[str], text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically (UTF-8 by default); returns the resolved destination path."""
    return atomic_write_bytes(path, text.encode(encoding))


def remove_live_temporaries() -> None:
    """Remove every temporary file an :func:`atomic_output` is writing right now (for signal handlers)."""
    with _registry_lock:
        names = list(_live_temporaries)
    for name in names:
        _remove(name)


def install_signal_cleanup() -> dict[int, Any]:
    """Make SIGINT and SIGTERM remove live temporary files, then stop the run: SIGINT raises
    :class:`KeyboardInterrupt`, SIGTERM :class:`SystemExit` (status 143), so ``finally`` blocks also run.

    Returns the handlers it replaced (give them to :func:`restore_signal_handlers` when the run is over, so a
    command line called from a script or from Blender leaves the process as it found it). Only from the main
    thread (Python's rule for signal handlers); elsewhere this does nothing and returns ``{}``.
    """
    if threading.current_thread() is not threading.main_thread():
        return {}

    def on_signal(signum: int, frame: object) -> None:
        remove_live_temporaries()
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise SystemExit(128 + signum)

    previous: dict[int, Any] = {}
    for signum in (signal.SIGINT, getattr(signal, "SIGTERM", None)):
        if signum is not None:
            previous[signum] = signal.signal(signum, on_signal)
    return previous


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
    """Hold SIGINT and SIGTERM until the body is done, then act on the first that came, as the handlers in force
    would have (a :class:`KeyboardInterrupt`, a :class:`SystemExit`). For loading Blender's ``bpy``: its bundled
    add-ons register inside error handlers, so a Ctrl+C raised in there was swallowed (the run went on and
    replaced the output file) or left Blender half set up (a segmentation fault at exit; a CLI review session)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    came: list[int] = []
    previous: dict[int, Any] = {}
    for signum in (signal.SIGINT, getattr(signal, "SIGTERM", None)):
        if signum is not None:
            previous[signum] = signal.signal(signum, lambda number, _frame: came.append(number))
    try:
        yield
    finally:
        restore_signal_handlers(previous)
    if came:
        handler = previous.get(came[0])
        if callable(handler):
            handler(came[0], None)
        elif came[0] == signal.SIGINT and handler is not signal.SIG_IGN:
            raise KeyboardInterrupt
        elif handler is signal.SIG_DFL:
            raise SystemExit(128 + came[0])


def restore_signal_handlers(previous: dict[int, Any]) -> None:
    """Put back the handlers :func:`install_signal_cleanup` replaced."""
    for signum, handler in previous.items():
        if handler is not None:
            signal.signal(signum, handler)
