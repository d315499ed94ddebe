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


class Ticker:
    """For work whose fraction is not known (reading a scene file): `label 12 s` on stderr when it
    is a terminal (or when forced), redrawn every `every` s from a daemon thread once the work has
    lasted `after` s, and cleared when it ends (a 95 MB PLY read for 27 s with nothing shown: a
    helper's probe). Ctrl-C reaches the work as before: the thread only writes."""

    def __init__(self, label: str, stream=None, enabled: bool | None = None, after: float = 1.0, every: float = 0.5):
        import threading

        self.label, self.stream, self.after, self.every = label, stream or sys.stderr, after, every
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="bvhlab ticker", daemon=True)
        self._width = 0

    def _run(self) -> None:
        started = time.monotonic()
        if self._stop.wait(self.after):
            return
        while not self._stop.is_set():
            text = f"\r{self.label} {time.monotonic() - started:.0f} s"
            self._width = max(self._width, len(text))
            self.stream.write(text)
            self.stream.flush()
            self._stop.wait(self.every)

    def __enter__(self):
        if self.enabled:
            self._thread.start()
        return self

    def __exit__(self, *exc):
        if self.enabled:
            self._stop.set()
            self._thread.join()
            if self._width:
                self.stream.write("\r" + " " * self._width + "\r")
                self.stream.flush()
