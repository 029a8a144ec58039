"""A progress line on stderr for stages that take more than a second (reading, meshing and solving).

Command-line tools stay silent when nobody watches: the line is drawn only when stderr is a terminal and ``--quiet``
was not given, so logs and pipes never receive carriage returns. A background thread redraws
``curved_fold: folding 4,600 segments: solving... 14 s`` twice a second once the stage has run for
:data:`DELAY_S`; the line is erased when the stage ends, so the regular output that follows is not interleaved.

Which step of the engine is running is read from the working thread's stack (the outermost frame in one of
``core``'s stage folders, :data:`STEPS`), so the engine needs no callback and the line still says "meshing" or
"solving" while a long numpy call runs.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time
from collections.abc import Iterator
from typing import TextIO

STEPS = (
    (os.sep + os.path.join("core", "pattern") + os.sep, "discretising"),
    (os.sep + os.path.join("core", "mesh") + os.sep, "meshing"),
    (os.sep + os.path.join("core", "solve") + os.sep, "solving"),
    (os.sep + os.path.join("core", "metrics") + os.sep, "measuring"),
    (os.sep + os.path.join("core", "io") + os.sep, "reading"),
)
"""Engine folder → the step named on the progress line while code from that folder runs."""


def current_step(thread_id: int) -> str | None:
    """The engine step the thread ``thread_id`` is in: the folder of its *outermost* frame in a :data:`STEPS`
    folder (the solver calls mesh helpers, but it is the solver the pipeline is waiting for), or None."""
    frame = sys._current_frames().get(thread_id)
    step = None
    while frame is not None:
        name = frame.f_code.co_filename
        for folder, label in STEPS:
            if folder in name:
                step = label
                break
        frame = frame.f_back
    return step


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
        worker = threading.get_ident()

        def draw() -> None:
            try:
                redraw()
            except Exception:  # a progress line must never disturb the run (a closed stream, say)
                return

        def redraw() -> None:
            if done.wait(DELAY_S):
                return
            while True:
                step = current_step(worker)
                text = f"{label}: {step}" if step else label
                self.stream.write(f"\rcurved_fold: {text}... {time.monotonic() - start:.0f} s\033[K")
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
