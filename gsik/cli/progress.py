"""A one-line progress bar on stderr for work that takes more than a second."""

from __future__ import annotations

import argparse
import sys
import time
from typing import TextIO


class Progress:
    """A one-line progress bar on a text stream, drawn only once the work has taken ``delay`` seconds.

    Call the instance as ``progress(done, total)``; :meth:`close` ends the line.
    Disabled, it does nothing.
    """

    def __init__(self, label: str, enabled: bool, stream: TextIO | None = None, width: int = 30,
                 delay: float = 1.0):
        self.label = label
        self.enabled = enabled
        self.stream = sys.stderr if stream is None else stream
        self.width = width
        self.delay = delay
        self._start = time.monotonic()
        self._drawn = False
        self._last = -1.0

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self._start < self.delay or (now - self._last < 0.1 and done < total):
            return
        self._last = now
        fraction = min(max(done / total, 0.0), 1.0) if total > 0 else 1.0
        filled = int(round(fraction * self.width))
        bar = "#" * filled + "-" * (self.width - filled)
        self.stream.write(f"\r{self.label} [{bar}] {100 * fraction:3.0f}% ({done}/{total})")
        self.stream.flush()
        self._drawn = True

    def close(self) -> None:
        if self._drawn:
            self.stream.write("\n")
            self.stream.flush()
            self._drawn = False

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def progress_for(args: argparse.Namespace, label: str) -> Progress:
    """The bar a command draws: on with ``--progress``, off with ``--no-progress``, else when stderr is a terminal."""
    enabled = args.progress if args.progress is not None else sys.stderr.isatty()
    return Progress(label, enabled)
