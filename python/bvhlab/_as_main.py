"""Ctrl-C while `python -m bvhlab` loads the package (numpy, the core): the package loads before
bvhlab/__main__.py, whose own guard then cannot catch it (a traceback in 8 of 8 tries in its first
100 ms: a helper's audit). The package imports this module first; while it loads, Ctrl-C exits
quietly with the command's 130, and `loaded()` gives Ctrl-C back to KeyboardInterrupt."""

from __future__ import annotations

import os
import signal
import sys
import threading


def _interrupted(*_) -> None:
    if sys.stderr is not None:  # None where it was closed (2>&-)
        sys.stderr.write("bvhlab: interrupted\n")
        sys.stderr.flush()
    # not SystemExit: a C extension's import (numpy's) turns what it meets into an ImportError
    os._exit(130)


#: `python -m bvhlab` itself (sys.argv[0] is "-m" while runpy finds the module, and the command
#: line names bvhlab: not its own `-m bvhlab.snapshot.worker`, nor another package's `-m` that
#: imports it), on the main thread, with Python's own Ctrl-C handler (one ignored or set by the
#: embedding program is left as it is).
ACTIVE = (
    sys.argv[:1] == ["-m"]
    and getattr(sys, "orig_argv", [])[-len(sys.argv) :][:1] == ["bvhlab"]  # where argv[0] stands
    and threading.current_thread() is threading.main_thread()
    and signal.getsignal(signal.SIGINT) is signal.default_int_handler
)
if ACTIVE:
    signal.signal(signal.SIGINT, _interrupted)


def loaded() -> None:
    """The package has loaded, or failed to: Ctrl-C raises KeyboardInterrupt again (__main__'s and
    the commands'), unless something else set its own handler meanwhile."""
    if ACTIVE and signal.getsignal(signal.SIGINT) is _interrupted:
        signal.signal(signal.SIGINT, signal.default_int_handler)
