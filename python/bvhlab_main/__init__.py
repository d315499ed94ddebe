"""The `bvhlab` command's entry point, outside the bvhlab package so that it runs before numpy and
the core load (importing anything inside the package imports the package first): Ctrl-C while they
load, about a second, ends the command as Ctrl-C ends it later ("bvhlab: interrupted", exit 130)
rather than with a traceback, or, inside numpy's own import, a chained ImportError and exit 1
(helper probes, 2026-12-06 and 12-07). After the command, Ctrl-C ends the process at once with
130 rather than raising inside the exit handlers (bpy's, where a .blend was read, printed a
traceback and exited 0); its output is flushed and its files written by then. A process started
with Ctrl-C ignored (a background job) keeps it ignored."""

from __future__ import annotations

import os
import signal
import sys


def main() -> int:
    interrupted: list[int] = []

    def on_sigint(signum, frame):
        interrupted.append(signum)
        raise KeyboardInterrupt

    previous = signal.getsignal(signal.SIGINT)
    handled = previous is signal.default_int_handler  # not where the process was started ignoring it
    if handled:
        signal.signal(signal.SIGINT, on_sigint)
    try:
        from bvhlab.cli import main as run
    except BaseException:
        if not interrupted:
            raise
        print("bvhlab: interrupted", file=sys.stderr)
        return 130
    finally:
        if handled:
            signal.signal(signal.SIGINT, previous)
    code = run()
    if handled:
        signal.signal(signal.SIGINT, _end_now)
    return code


def _end_now(signum, frame) -> None:
    """Ctrl-C after the command's work: the process ends here, the exit handlers not run further."""
    os._exit(130)
