"""A terminal progress bar for long work (builds, renders), with no dependencies."""

from __future__ import annotations

import sys
import time


class ProgressBar:
    """Call with a fraction in [0, 1]; draws `label [#####.....] 42%` on stderr when it is a
    terminal (or when forced), at most every 0.1 s. Returns True so it can be a build callback."""

    def __init__(self, label: str, stream=None, enabled: bool | None = None, width: int = 30):
        self.label, self.stream, self.width = label, stream or sys.stderr, width
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self._last = 0.0
        self._shown = False

    def __call__(self, fraction: float) -> bool:
        now = time.monotonic()
        if self.enabled and (fraction >= 1.0 or now - self._last >= 0.1):
            self._last = now
            filled = int(round(self.width * min(max(fraction, 0.0), 1.0)))
            self.stream.write(f"\r{self.label} [{'#' * filled}{'.' * (self.width - filled)}] {fraction:4.0%}")
            self.stream.flush()
            self._shown = True
        return True

    def close(self) -> None:
        if self._shown:
            self.stream.write("\r" + " " * (len(self.label) + self.width + 10) + "\r")
            self.stream.flush()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
