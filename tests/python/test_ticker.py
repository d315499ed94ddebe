"""The CLI's elapsed-time line while a scene file is read (bvhlab._progress.Ticker; a helper's probe:
a 95 MB PLY read for 27 s with nothing on the terminal): shown after a second, redrawn, cleared,
never shown off a terminal, and the work's own exception passes through with the line cleared."""

import io
import threading
import time

import pytest

from bvhlab._progress import Ticker
from bvhlab.cli import options


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_line_counts_seconds_and_is_cleared():
    out = Terminal()
    with Ticker("reading big.ply (95 MB)", stream=out, after=0.05, every=0.05):
        time.sleep(0.4)
    text = out.getvalue()
    assert text.count("\rreading big.ply (95 MB) 0 s") >= 3, text
    assert text.endswith("\r" + " " * len("\rreading big.ply (95 MB) 0 s") + "\r"), repr(text[-60:])
    assert not any(t.name == "bvhlab ticker" for t in threading.enumerate())


def test_short_work_and_pipes_show_nothing():
    out = Terminal()
    with Ticker("reading small.obj", stream=out):  # done within its first second
        pass
    piped = io.StringIO()
    with Ticker("reading big.ply", stream=piped, after=0.0, every=0.01):
        time.sleep(0.1)
    assert out.getvalue() == "" and piped.getvalue() == ""


def test_an_error_in_the_work_passes_through_and_clears_the_line():
    out = Terminal()
    with pytest.raises(KeyboardInterrupt), Ticker("reading big.ply", stream=out, after=0.0, every=0.01):
        time.sleep(0.05)
        raise KeyboardInterrupt
    assert out.getvalue().endswith("\r") and not any(t.name == "bvhlab ticker" for t in threading.enumerate())


def test_the_cli_reads_scene_files_with_it(tmp_path, monkeypatch):
    shown = []
    monkeypatch.setattr(options, "Ticker", lambda label, **kw: shown.append(label) or Ticker(label, **kw))
    path = tmp_path / "tri.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    scene, name = options.read_scene(str(path))
    assert name == "tri" and shown == ["reading tri.obj"]
    options.read_scene("gen:random_spheres")  # no file: no line
    assert shown == ["reading tri.obj"]
