"""The `bvhlab` command's entry point, outside the bvhlab package so that it runs before numpy and
the core load (importing anything inside the package imports the package first): Ctrl-C while they
load, about a second, ends the command as Ctrl-C ends it later ("bvhlab: interrupted", exit 130)
rather than with a traceback, or, inside numpy's own import, a chained ImportError and exit 1
(helper probes, 2026-12-06 and 12-07). After the command, Ctrl-C no longer reaches the exit
handlers (bpy's, where a .blend was read, printed a traceback and exited 0)."""

from __future__ import annotations

import signal
import sys


def main() -> int:
    interrupted: list[int] = []

    def on_sigint(signum, frame):
        interrupted.append(signum)
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, on_sigint)
    try:
        from bvhlab.cli import main as run
    except BaseException:
        if not interrupted:
            raise
        print("bvhlab: interrupted", file=sys.stderr)
        return 130
    finally:
        signal.signal(signal.SIGINT, previous)
    code = run()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the exit handlers run whole
    return code
