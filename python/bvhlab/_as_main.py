"""Ctrl-C while `python -m bvhlab` loads the package (numpy, the core): the package loads before
bvhlab/__main__.py, whose own guard then cannot catch it (a traceback in 8 of 8 tries in its first
100 ms: a helper's audit). The package imports this module first; while it loads, Ctrl-C exits
quietly with the command's 130, and `loaded()` gives Ctrl-C back to KeyboardInterrupt."""

from __future__ import annotations

import signal
import sys
import threading


def _interrupted(*_) -> None:
    sys.stderr.write("bvhlab: interrupted\n")
    raise SystemExit(130)


#: `python -m bvhlab` (sys.argv[0] is "-m" while runpy finds the module), on the main thread, with
#: Python's own Ctrl-C handler (one ignored or set by the embedding program is left as it is).
ACTIVE = (
    sys.argv[:1] == ["-m"]
    and threading.current_thread() is threading.main_thread()
    and signal.getsignal(signal.SIGINT) is signal.default_int_handler
)
if ACTIVE:
    signal.signal(signal.SIGINT, _interrupted)


def loaded() -> None:
    """The package has loaded: Ctrl-C raises KeyboardInterrupt again (__main__'s and the commands')."""
    if ACTIVE:
        signal.signal(signal.SIGINT, signal.default_int_handler)
