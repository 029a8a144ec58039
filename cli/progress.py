"""A progress line on stderr for stages that take more than a second (reading, meshing and solving).

Command-line tools stay silent when nobody watches: the line is drawn only when stderr is a terminal and ``--quiet``
was not given, so logs and pipes never receive carriage returns. A background thread redraws
``curved_fold: folding (meshing, solving)... 4 s`` twice a second once the stage has run for :data:`DELAY_S`; the
line is erased when the stage ends, so the regular output that follows is not interleaved with it.
"""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from collections.abc import Iterator
from typing import TextIO

DELAY_S = 1.0
"""A stage shorter than this draws nothing."""

REDRAW_S = 0.5
"""Seconds between redraws of the line."""


class Progress:
    """Progress lines for one command-line run; ``enabled`` defaults to "stderr is a terminal and not quiet"."""

    def __init__(self, *, quiet: bool = False, stream: TextIO | None = None, enabled: bool | None = None) -> None:
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            isatty = getattr(self.stream, "isatty", None)
            enabled = not quiet and bool(isatty and isatty())
        self.enabled = enabled
        self.drawn = 0
        """How many times a line was drawn (for tests)."""

    @contextlib.contextmanager
    def stage(self, label: str) -> Iterator[None]:
        """Show ``label`` and the elapsed seconds while the block runs longer than :data:`DELAY_S`."""
        if not self.enabled:
            yield
            return
        done = threading.Event()
        start = time.monotonic()
        shown = [False]

        def draw() -> None:
            if done.wait(DELAY_S):
                return
            while True:
                self.stream.write(f"\rcurved_fold: {label}... {time.monotonic() - start:.0f} s")
                self.stream.flush()
                shown[0] = True
                self.drawn += 1
                if done.wait(REDRAW_S):
                    return

        thread = threading.Thread(target=draw, name="curved_fold progress", daemon=True)
        thread.start()
        try:
            yield
        finally:
            done.set()
            thread.join()
            if shown[0]:
                self.stream.write("\r\033[K")  # erase the line
                self.stream.flush()
