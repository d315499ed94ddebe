"""Issue 39.8: every file bvhlab writes is either the old one or the whole new one. The writer
(bvhlab._atomic) writes a temporary beside the file, fsyncs it and renames it into place; an error,
Ctrl-C or a file-size limit leaves the old bytes and no temporary, and the error names the file."""

import os
import re
import stat
from pathlib import Path

import numpy as np
import pytest
from child import default_sigint, run_python

import bvhlab
from bvhlab._atomic import WriteError, replacing, staged_folder, write_bytes, write_text

REPO = Path(__file__).resolve().parents[2]


def _listing(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_replaces_the_whole_file_and_leaves_no_temporary(tmp_path):
    path = tmp_path / "a.json"
    path.write_text("old")
    write_text(path, '{"new": 1}\n')
    assert path.read_text() == '{"new": 1}\n' and _listing(tmp_path) == ["a.json"]
    write_bytes(tmp_path / "b.png", b"\x89PNG")
    assert (tmp_path / "b.png").read_bytes() == b"\x89PNG" and _listing(tmp_path) == ["a.json", "b.png"]


@pytest.mark.parametrize("error", [ValueError("bad row"), KeyboardInterrupt()])
def test_an_error_while_writing_keeps_the_old_file(tmp_path, error):
    """The writer fails half-way (an exception, Ctrl-C): the old bytes stay, the temporary goes."""
    path = tmp_path / "table.csv"
    path.write_bytes(b"method,frame_ms\nmedian,41.8\n")
    with pytest.raises(type(error)):
        with replacing(path, text=True) as f:
            f.write("method,frame_ms\n" * 10000)
            raise error
    assert path.read_bytes() == b"method,frame_ms\nmedian,41.8\n"
    assert _listing(tmp_path) == ["table.csv"]


def test_a_real_sigint_mid_write_keeps_the_old_file(tmp_path):
    """SIGINT delivered to the process while the bytes are being written (KeyboardInterrupt at the
    next bytecode), as Ctrl-C in a terminal would."""
    path = tmp_path / "good.png"
    path.write_bytes(b"old png")
    done = run_python(
        f"""
        import os, signal
        from bvhlab._atomic import replacing
        try:
            with replacing({str(path)!r}) as f:
                for i in range(1000):
                    f.write(b"x" * 4096)
                    if i == 500:
                        os.kill(os.getpid(), signal.SIGINT)
        except KeyboardInterrupt:
            print("interrupted")
        """,
        timeout=60,
        preexec_fn=default_sigint,
    )
    assert done.stdout.strip() == "interrupted", done.stderr
    assert path.read_bytes() == b"old png" and _listing(tmp_path) == ["good.png"]


def test_a_name_near_the_limit_in_bytes_is_written(tmp_path):
    """The temporary's name was the target's cut by characters: 120 'ü' (240 bytes, a valid name)
    made a 259-byte temporary, and the write failed after all the work (helper probe, 2026-12-07)."""
    for name in ("ü" * 120 + ".json", "€" * 81 + ".json", "a" * 250 + ".json"):
        target = tmp_path / name
        assert len(os.fsencode(name)) <= 255
        write_text(target, "{}")
        assert target.read_text() == "{}"
    assert len(list(tmp_path.iterdir())) == 3  # no temporary left


def test_permissions_are_kept_or_follow_the_umask(tmp_path):
    """A temporary file would be 0600: a replaced file keeps its mode, a new one gets open()'s."""
    old = tmp_path / "old.json"
    old.write_text("{}")
    old.chmod(0o640)
    write_text(old, "[]")
    assert stat.S_IMODE(old.stat().st_mode) == 0o640
    umask = os.umask(0o022)
    try:
        write_text(tmp_path / "new.json", "[]")
    finally:
        os.umask(umask)
    assert stat.S_IMODE((tmp_path / "new.json").stat().st_mode) == 0o644


def test_a_symbolic_link_is_written_through(tmp_path):
    """As open() would: the link stays a link, the file it points to gets the new bytes."""
    real = tmp_path / "real.png"
    real.write_bytes(b"old")
    link = tmp_path / "link.png"
    link.symlink_to(real)
    write_bytes(link, b"new")
    assert link.is_symlink() and real.read_bytes() == b"new"


def test_a_fifo_as_output_is_refused_without_blocking(tmp_path):
    """open() of a FIFO for writing blocks until a reader comes; the writer refuses it instead."""
    fifo = tmp_path / "out.png"
    os.mkfifo(fifo)
    done = run_python(
        f"""
        import numpy as np, bvhlab
        try:
            bvhlab.save_png(np.zeros((2, 2, 3), np.float32), {str(fifo)!r})
        except OSError as e:
            print(e)
        """,
        timeout=30,
    )
    assert f"cannot write {fifo}: it exists and is a FIFO (named pipe), not a regular file" in done.stdout, done
    assert stat.S_ISFIFO(fifo.stat().st_mode)


def test_a_file_size_limit_keeps_the_old_png_and_names_it(tmp_path):
    """RLIMIT_FSIZE (a second way to run out of room, without mounting anything): writes past it fail
    with EFBIG (Python ignores SIGXFSZ), as a full disk fails with ENOSPC."""
    path = tmp_path / "good.png"
    bvhlab.save_png(np.zeros((2, 2, 3), np.float32), path)
    old = path.read_bytes()
    done = run_python(
        f"""
        import resource, numpy as np, bvhlab
        resource.setrlimit(resource.RLIMIT_FSIZE, (1024, resource.RLIM_INFINITY))
        noise = np.random.default_rng(1).random((64, 64, 3)).astype(np.float32)  # ~16 KB of PNG
        try:
            bvhlab.save_png(noise, {str(path)!r})
        except OSError as e:
            print(type(e).__name__, e.errno, e)
        """,
        timeout=60,
    )
    assert done.stdout.strip() == f"WriteError 27 cannot write {path}: File too large", done
    assert path.read_bytes() == old and _listing(tmp_path) == ["good.png"]


def test_concurrent_writers_leave_one_whole_file(tmp_path):
    """25 processes writing one PNG at once: the file is one of theirs, whole; no temporaries left."""
    path = tmp_path / "shared.png"
    done = run_python(
        f"""
        import multiprocessing as mp, numpy as np, bvhlab
        def write(i):
            bvhlab.save_png(np.full((40, 40, 3), i / 25, np.float32), {str(path)!r})
        if __name__ == "__main__":
            with mp.get_context("fork").Pool(25) as pool:
                pool.map(write, range(25))
        """,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    from png_reader import read_png

    image = read_png(path)
    assert image.shape == (40, 40, 4) and len(np.unique(image[..., 0])) == 1
    assert _listing(tmp_path) == ["shared.png"]


# What writes a file without the atomic writer: open(.., "w"/"wb"/"a"), Path.write_text/bytes,
# matplotlib's savefig/imsave to a name, numpy's save/savez to a name, a ZipFile opened on a name.
# (a member of a zip archive written inside `replacing`, archive.open(name, "w"), is no file by name)
_DIRECT_WRITE = re.compile(
    r"""(?<!archive\.)open\([^)]*["'][wax]b?\+?["']|\.write_(text|bytes)\(|\.(savefig|imsave)\((?!f\b)|"""
    r"""np\.(save|savez|savez_compressed)\((?!f\b|buffer\b)|ZipFile\((?!f\b)[^)]*["']w["']|\.tofile\("""
)


def test_every_writer_of_the_package_and_the_addon_goes_through_the_atomic_writer():
    """One writer everywhere (issue 39.8): no module of python/bvhlab or addon/ writes a file by
    name (bvhlab._atomic itself aside)."""
    offenders = []
    for root in (REPO / "python" / "bvhlab", REPO / "addon"):
        for source in root.rglob("*.py"):
            if source.name == "_atomic.py" or "wheels" in source.parts:
                continue
            for number, line in enumerate(source.read_text().splitlines(), 1):
                if _DIRECT_WRITE.search(line) and not line.lstrip().startswith("#"):
                    offenders.append(f"{source.relative_to(REPO)}:{number}: {line.strip()}")
    assert offenders == []


def _interrupting_renames(folder) -> str:
    """A child's script start: `folder`, and every rename of bvhlab._atomic followed by a real
    SIGINT to the process (after the first, the other files are still old)."""
    return f"""
        import os, signal
        from pathlib import Path
        from bvhlab import _atomic
        folder = Path({str(folder)!r})
        real = os.replace
        def replace_then_interrupt(a, b):
            real(a, b)
            os.kill(os.getpid(), signal.SIGINT)
        _atomic.os.replace = replace_then_interrupt
        """


def test_files_written_together_are_all_old_or_all_new(tmp_path):
    """`bvhlab animate` wrote its CSV, JSON and plot one after another, and Ctrl-C while the plot
    was drawn left the new table and report beside the old plot (probe). write_together stages all
    of them first: a real SIGINT arriving between the renames is held until the last is in place
    (then raised), and an error while staging leaves every file as it was, without temporaries."""
    names = ("animate.csv", "animate.json", "animate.png")
    for name in names:
        (tmp_path / name).write_bytes(b"old " + name.encode())
    done = run_python(
        _interrupting_renames(tmp_path)
        + f"""
        try:
            _atomic.write_together({{folder / n: b"new " + n.encode() for n in {names!r}}})
        except KeyboardInterrupt:
            print("interrupted after the renames")
        """,
        timeout=60,
        preexec_fn=default_sigint,
    )
    assert done.stdout.strip() == "interrupted after the renames", done.stderr
    assert [(tmp_path / n).read_bytes() for n in names] == [b"new " + n.encode() for n in names]
    assert _listing(tmp_path) == sorted(names)
    # an error while staging (the last target is a folder): every file as it was
    from bvhlab._atomic import WriteError, write_together

    (tmp_path / "plot.png").mkdir()
    files = {tmp_path / "animate.csv": b"newer", tmp_path / "animate.json": b"newer", tmp_path / "plot.png": b"x"}
    with pytest.raises(WriteError, match="plot.png"):
        write_together(files)
    assert [(tmp_path / n).read_bytes() for n in names] == [b"new " + n.encode() for n in names]
    assert _listing(tmp_path) == sorted([*names, "plot.png"])


def test_an_interrupt_held_while_files_are_written_together_goes_to_the_handler_there_was(tmp_path):
    """The held SIGINT was raised as KeyboardInterrupt whatever handled it before: ignored (a
    background job's) or a caller's own handler (review). It now goes to that handler."""
    done = run_python(
        _interrupting_renames(tmp_path)
        + """
        for label, handler in (("ignored", signal.SIG_IGN), ("own", lambda *_: print("own handler"))):
            signal.signal(signal.SIGINT, handler)
            try:
                _atomic.write_together({folder / "a": b"1", folder / "b": b"2"})
                print(label, "written")
            except KeyboardInterrupt:
                print(label, "KeyboardInterrupt")
        """,
        timeout=60,
        preexec_fn=default_sigint,
    )
    assert done.stdout.splitlines()[:3] == ["ignored written", "own handler", "own written"], done.stdout


def test_a_staged_folder_moves_its_files_in_together_or_not_at_all(tmp_path):
    (tmp_path / "a.txt").write_text("old a")
    (tmp_path / "b.txt").write_text("old b")
    with pytest.raises(KeyboardInterrupt), staged_folder(tmp_path) as stage:
        (stage / "a.txt").write_text("new a")
        raise KeyboardInterrupt  # before b was written
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt"]
    assert (tmp_path / "a.txt").read_text() == "old a"
    with staged_folder(tmp_path) as stage:
        write_text(stage / "a.txt", "new a")
        (stage / "sub").mkdir()
        write_text(stage / "sub" / "c.txt", "c")
    assert [(tmp_path / n).read_text() for n in ("a.txt", "b.txt", "sub/c.txt")] == ["new a", "old b", "c"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt", "sub"]
    # an error writing a staged file names the file it was to become
    (tmp_path / "d.txt").mkdir()
    with pytest.raises(WriteError, match=r"cannot write .*/d\.txt/x: "), staged_folder(tmp_path) as stage:
        raise WriteError(28, "No space left on device", str(stage / "d.txt" / "x"))
