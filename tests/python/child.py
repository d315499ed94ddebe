"""Runs Python code in a child process, so that a crash (abort, segfault) fails one test instead
of ending the test run."""

import signal
import subprocess
import sys
import textwrap


def default_sigint() -> None:
    """preexec_fn for a child that a test sends SIGINT: the signal's default disposition, as a
    terminal's Ctrl-C finds it. A test run started in the background of a shell without job control
    inherits SIGINT ignored, and a Python started with it ignored installs no KeyboardInterrupt
    handler, so the Ctrl-C tests would fail there for a reason that is not the code's."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def run_python(code: str, timeout: float = 300, **popen) -> subprocess.CompletedProcess:
    """Runs `code` (dedented) with this interpreter; returns the finished process (text output)."""
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=timeout, **popen
    )


def check_python(code: str, timeout: float = 300) -> str:
    """Runs `code` in a child; fails with its output unless it exits 0. Returns its stdout."""
    done = run_python(code, timeout)
    assert done.returncode == 0, f"exit {done.returncode}\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    return done.stdout
