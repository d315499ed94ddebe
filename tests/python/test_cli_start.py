"""The `bvhlab` command before and after its work (helper probes, 2026-12-06 and 12-07): Ctrl-C
while numpy and the core load ended in a traceback (or, inside numpy's own import, a chained
ImportError and exit 1); a path too long for the system, checked while the arguments are read,
in one ("OSError: [Errno 36] File name too long", exit 1). The entry point (python/bvhlab_main)
is run in this process with the package's import made to receive a SIGINT."""

import builtins
import os
import signal
import sys

import bvhlab_main
import pytest

from bvhlab.cli import main


@pytest.fixture()
def cli_unloaded(monkeypatch):
    """bvhlab.cli forgotten, so that the entry point imports it again (through `import_hook`)."""
    monkeypatch.delitem(sys.modules, "bvhlab.cli")
    real = builtins.__import__
    hooks = []

    def importing(name, *args, **kwargs):
        if name == "bvhlab.cli" and hooks:
            hooks.pop()()
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", importing)
    return hooks


def _sigint() -> None:
    os.kill(os.getpid(), signal.SIGINT)


def _sigint_in_a_c_import() -> None:
    """As numpy's C import turns the KeyboardInterrupt it meets into an ImportError."""
    try:
        _sigint()
    except KeyboardInterrupt:
        raise ImportError("PyCapsule_Import could not import module 'datetime'") from None


@pytest.mark.parametrize("hook", [_sigint, _sigint_in_a_c_import])
def test_ctrl_c_while_the_package_loads_ends_quietly(cli_unloaded, hook, capsys):
    before = signal.getsignal(signal.SIGINT)
    cli_unloaded.append(hook)
    assert bvhlab_main.main() == 130
    assert capsys.readouterr().err == "bvhlab: interrupted\n"
    assert signal.getsignal(signal.SIGINT) is before  # put back


def test_an_import_error_without_ctrl_c_is_raised(cli_unloaded):
    def broken():
        raise ImportError("a broken install")

    cli_unloaded.append(broken)
    with pytest.raises(ImportError, match="a broken install"):
        bvhlab_main.main()


def test_the_command_runs_and_then_ctrl_c_ends_the_process_at_once(monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", ["bvhlab", "scenes"])
    before = signal.getsignal(signal.SIGINT)
    try:
        assert bvhlab_main.main() == 0
        assert "gen:five_spheres" in capsys.readouterr().out
        assert signal.getsignal(signal.SIGINT) is bvhlab_main._end_now  # not inside the exit handlers
    finally:
        signal.signal(signal.SIGINT, before)


def test_ctrl_c_after_the_work_ends_with_130_and_no_traceback(tmp_path):
    """The command's exit handlers (here one that waits, as bpy's and Dask's may) take no
    KeyboardInterrupt: the process ends at once, with 130."""
    import subprocess
    import time

    script = tmp_path / "run.py"
    script.write_text(
        "import atexit, sys, time\n"
        "atexit.register(lambda: (print('in exit', flush=True), time.sleep(30)))\n"
        "import bvhlab_main\n"
        "sys.argv = ['bvhlab', 'scenes']\n"
        "sys.exit(bvhlab_main.main())\n"
    )
    child = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    printed = []
    for line in child.stdout:
        if line.startswith("in exit"):
            break
        printed.append(line)
    assert any("gen:five_spheres" in line for line in printed), printed  # the command's output, whole
    time.sleep(0.2)
    child.send_signal(signal.SIGINT)
    assert child.wait(20) == 130
    assert "Traceback" not in child.stderr.read()


def test_a_process_started_ignoring_ctrl_c_keeps_ignoring_it(monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", ["bvhlab", "scenes"])
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        assert bvhlab_main.main() == 0
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, before)


@pytest.mark.parametrize(
    "args",
    [
        ["build", "a" * 300 + ".obj"],
        ["build", "gen:five_spheres", "--json", "a" * 300 + ".json"],
        ["render", "gen:five_spheres", "--out", "a" * 300 + "/x.png"],
    ],
)
def test_a_path_too_long_while_the_arguments_are_read_is_one_line(args, capsys):
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"bvhlab {args[0]}: error: ") and "File name too long" in err and len(err.splitlines()) == 1


def test_ctrl_c_while_python_m_bvhlab_loads_the_package_ends_quietly():
    """`python -m bvhlab` loads the package before its __main__, whose guard then cannot catch a
    Ctrl-C (a traceback in 8 of 8 tries in the first 100 ms: a helper's audit). The package's first
    import (bvhlab._as_main) makes it a quiet 130 while the rest loads. Here a child whose argv[0] is
    "-m", as runpy sets it, receives SIGINT as the package imports numpy; a plain import is left as
    it is (KeyboardInterrupt)."""
    import subprocess

    child = (
        "import builtins, os, signal, sys\n"
        "sys.argv = [sys.argv[1]]\n"
        "sys.orig_argv = [sys.executable, sys.argv[0], 'bvhlab']  # as `python -m bvhlab` has them\n"
        "real = builtins.__import__\n"
        "def hook(name, *a, **k):\n"
        "    if name.startswith('numpy'):\n"
        "        builtins.__import__ = real\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "    return real(name, *a, **k)\n"
        "builtins.__import__ = hook\n"
        "import bvhlab\n"
        "print('loaded')\n"
    )
    for argv0, code, last in (("-m", 130, "bvhlab: interrupted"), ("-c", -signal.SIGINT, "KeyboardInterrupt")):
        done = subprocess.run(
            [sys.executable, "-c", child, argv0],
            capture_output=True,
            text=True,
            timeout=120,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        assert done.returncode == code and done.stderr.strip(), done.stderr
        assert done.stderr.strip().splitlines()[-1] == last, done.stderr
        assert ("Traceback" in done.stderr) == (argv0 == "-c")
