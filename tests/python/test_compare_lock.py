"""Issue 39: two `bvhlab compare` runs into one folder left a mix of both runs' tables and figures.
A run holds a lock on its --out folder; a second one is refused at once, naming the holder, and
writes nothing; a lock left by a run that died does not block the next."""

import os
import signal
import subprocess
import sys
import time

import pytest
from cli_args import QUICK_COMPARE

from bvhlab._folder_lock import LOCK_NAME, FolderBusy, folder_lock


def compare(out, *extra, timeout=300):
    return subprocess.run(
        [sys.executable, "-m", "bvhlab", "compare", "gen:five_spheres", *QUICK_COMPARE, *extra, "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def test_a_second_run_into_a_held_folder_is_refused(tmp_path):
    """Two real `compare` processes: the first is stopped (SIGSTOP) as soon as it holds the folder,
    so the second surely starts while it runs; the second exits 2 naming the first, which then
    (SIGCONT) finishes alone."""
    out = tmp_path / "out"
    first = subprocess.Popen(
        [sys.executable, "-m", "bvhlab", "compare", "gen:five_spheres", *QUICK_COMPARE, "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 120
        while not (out / LOCK_NAME).exists() or not (out / LOCK_NAME).read_text():
            assert first.poll() is None and time.monotonic() < deadline, first.communicate()
            time.sleep(0.01)
        os.kill(first.pid, signal.SIGSTOP)
        second = compare(out)
    finally:
        os.kill(first.pid, signal.SIGCONT)
        stdout, stderr = first.communicate(timeout=600)
    assert second.returncode == 2, second.stderr
    line = second.stderr.strip().splitlines()[-1]
    assert line.startswith(
        f"bvhlab compare: error: {out} is being written by another run (bvhlab compare, pid {first.pid} "
    )
    assert line.endswith("wait for it to finish or choose another folder") and second.stdout == ""
    assert first.returncode == 0, stderr
    assert "| median |" in (out / "table.md").read_text()  # the first run's table, whole
    assert not (out / LOCK_NAME).exists()


def test_a_held_folder_is_left_untouched(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "table.csv").write_text("the other run's\n")
    with folder_lock(out, "a test"):
        done = compare(out)
    assert done.returncode == 2 and f"(a test, pid {os.getpid()} on " in done.stderr
    assert sorted(p.name for p in out.iterdir()) == ["table.csv"]
    assert (out / "table.csv").read_text() == "the other run's\n"


def test_a_lock_file_left_by_a_dead_run_does_not_block(tmp_path):
    """A run killed with SIGKILL leaves its lock file (the kernel drops the lock itself)."""
    out = tmp_path / "out"
    out.mkdir()
    (out / LOCK_NAME).write_text("bvhlab compare, pid 999999 on gone, started long ago\n")
    done = compare(out)
    assert done.returncode == 0, done.stderr
    assert (out / "table.csv").exists() and not (out / LOCK_NAME).exists()


def test_the_lock_is_one_holder_at_a_time(tmp_path):
    with folder_lock(tmp_path, "first"):
        with pytest.raises(FolderBusy, match=r"is being written by another run \(first, pid"):
            # flock locks belong to an open file: a second open in this process is a second holder
            with folder_lock(tmp_path, "second"):
                pass
    with folder_lock(tmp_path, "third"):
        assert "third" in (tmp_path / LOCK_NAME).read_text()


def test_an_interrupted_compare_leaves_the_folder_as_it_was(tmp_path, monkeypatch):
    # its files went in one at a time: an interrupt while the charts were drawn left the new tables
    # beside the old charts; now they are staged and moved in together at the end
    from cli_args import QUICK_COMPARE as quick

    from bvhlab.cli import compare_cmd, main

    out = tmp_path / "out"
    assert main(["compare", "gen:five_spheres", *quick, "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert {"table.csv", "table.md", "times.png"} <= set(before)

    def interrupted(*_):
        raise KeyboardInterrupt

    monkeypatch.setattr(compare_cmd, "_write_charts", interrupted)  # after the tables are written
    assert main(["compare", "gen:five_spheres", *quick, "--frames", "6", "--out", str(out)]) == 130
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # no staging folder left either
