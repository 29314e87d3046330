"""Progress of ``impact-harness report`` on stderr, once it has taken a while.

A warm report takes under a second and says nothing until its last line; a cold one (every
figure redrawn after a change to the report's code: ~20 s on two cores, minutes at 1,000
scenarios) says, every :data:`EVERY_S` seconds from :data:`AFTER_S` on, the step it is at
and, while figures are drawn, how many of them are written. The figures are drawn by forked
workers: a figure counts as written once its PNG is newer than the step's start.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path

#: Seconds of silence before the first progress line (a warm report ends well within them).
AFTER_S = 2.0
#: Seconds between progress lines.
EVERY_S = 5.0


class Progress:
    """The report's current step, printed as ``report: STEP (N s)`` by a background thread
    from :data:`AFTER_S` on; :meth:`close` stops it. A step with ``figures`` (the PNG paths
    being drawn) adds ``k of n figures written``."""

    def __init__(self, stream=None, after_s: float = AFTER_S, every_s: float = EVERY_S,
                 label: str = "report"):
        self.stream = stream if stream is not None else sys.stderr
        self.after_s, self.every_s, self.label = after_s, every_s, label
        self.started = time.monotonic()
        self._step = "starting"
        self._figures: list[Path] = []
        self._figures_since = 0.0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="report-progress", daemon=True)
        self._thread.start()

    def step(self, text: str) -> None:
        """The step the report is at now (``"building the page"``)."""
        with self._lock:
            self._step = text

    def drawing(self, figures: Sequence[Path]) -> None:
        """The figures being drawn from now on (their PNG paths)."""
        with self._lock:
            self._figures = list(figures)
            self._figures_since = time.time() - 1.0  # a file system's mtime may lag by a tick

    def line(self) -> str:
        """The progress line as it would be printed now."""
        with self._lock:
            step, figures, since = self._step, self._figures, self._figures_since
        text = f"{self.label}: {step}"
        if figures:
            written = sum(1 for path in figures if _newer(path, since))
            text += f"; {written} of {len(figures)} figures written"
        return f"{text} ({time.monotonic() - self.started:.0f} s)"

    def _run(self) -> None:
        if self._stop.wait(self.after_s):
            return
        while True:
            print(self.line(), file=self.stream, flush=True)
            if self._stop.wait(self.every_s):
                return

    def close(self) -> None:
        self._stop.set()
        self._thread.join()

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *_) -> None:
        self.close()


class Silent:
    """:class:`Progress` that prints nothing (the library's callers, the tests)."""

    def step(self, text: str) -> None:
        pass

    def drawing(self, figures: Sequence[Path]) -> None:
        pass


def _newer(path: Path, since: float) -> bool:
    try:
        return path.stat().st_mtime >= since
    except OSError:
        return False
