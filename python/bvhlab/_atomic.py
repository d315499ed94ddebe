"""Writing a file so that it ends up either as it was or whole (issue 39.8): the bytes go to a
temporary file in the same folder, which is flushed to the disk (fsync) and then renamed over the
old one (os.replace, atomic within one file system). A full disk, a signal, an exception in the
writer or Ctrl-C leave the old file untouched and no temporary behind, and the error names the file
("cannot write out/x.png: No space left on device").

Every file bvhlab writes goes through `replacing` (or `write_bytes`/`write_text`, built on it):
PNGs, stats and tables, charts and figures, scene files, the add-on's exports."""

from __future__ import annotations

import contextlib
import io
import os
import secrets
import shutil
import signal
import stat
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import IO, BinaryIO, Literal, TextIO, overload

#: Longest file name most file systems accept; the temporary's name must fit too.
_NAME_MAX = 255
_KINDS = {
    stat.S_IFIFO: "a FIFO (named pipe)",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFSOCK: "a socket",
    stat.S_IFDIR: "a folder",
}


class WriteError(OSError):
    """A file that could not be written; what was there before is left as it was. An OSError with
    the errno of the cause and the file as `filename`; str(): "cannot write PATH: REASON"."""

    def __str__(self) -> str:
        return f"cannot write {self.filename}: {self.strerror}"


def _write_error(path: Path, error: OSError) -> WriteError:
    return WriteError(error.errno or 0, error.strerror or str(error), str(path))


def _target(path: Path) -> Path:
    """Where the bytes go: a symbolic link's target (as open() would write), refusing anything
    that exists and is not a regular file (a FIFO would block the writer; a device or folder would
    be replaced)."""
    target = Path(os.path.realpath(path)) if path.is_symlink() else path
    try:
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        return target
    if not stat.S_ISREG(mode):
        kind = _KINDS.get(stat.S_IFMT(mode), "not a regular file")
        raise WriteError(0, f"it exists and is {kind}, not a regular file", str(path))
    return target


def _create_temporary(target: Path) -> tuple[Path, int]:
    """A new, empty file beside `target`, created with the permissions open() would give (0666
    less the umask) or the old file's; returns its path and descriptor."""
    # within the system's limit in bytes, not characters (a name of 120 'ü' is 240 bytes: its
    # temporary came to 259 and the write failed after the work); a character cut in two, or a
    # name that is no UTF-8, keeps its bytes (fsdecode's surrogate escapes)
    stem = os.fsdecode(os.fsencode(target.name)[: _NAME_MAX - 20])
    for _ in range(100):
        temporary = target.with_name(f".{stem}.{secrets.token_hex(4)}.tmp")
        try:
            fd = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
        except FileExistsError:
            continue  # another writer's temporary: never touch it
        with contextlib.suppress(FileNotFoundError, PermissionError):
            os.fchmod(fd, stat.S_IMODE(os.stat(target).st_mode))
        return temporary, fd
    raise FileExistsError(f"no free temporary name beside {target}")


def _sync_folder(folder: Path) -> None:
    """Makes the rename itself durable where the file system allows it (not every one does)."""
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY | os.O_CLOEXEC)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


@overload
def replacing(path, *, text: Literal[False] = False) -> contextlib.AbstractContextManager[BinaryIO]: ...
@overload
def replacing(path, *, text: Literal[True]) -> contextlib.AbstractContextManager[TextIO]: ...


def replacing(path, *, text: bool = False) -> contextlib.AbstractContextManager[IO]:
    """`with replacing(path) as f: f.write(...)` writes `path` as a whole or not at all. `f` is a
    binary file, or with `text` a UTF-8 text file without newline translation (what csv wants). On
    any error, KeyboardInterrupt included, the temporary is removed and the error raised again; an
    OSError becomes a WriteError naming `path`."""
    return _replacing(Path(path), text)


@contextlib.contextmanager
def _replacing(path: Path, text: bool) -> Iterator[IO]:
    temporary = None
    try:
        target = _target(path)
        temporary, fd = _create_temporary(target)
        raw = os.fdopen(fd, "wb")
        with io.TextIOWrapper(raw, encoding="utf-8", newline="") if text else raw as f:
            yield f
            f.flush()
            os.fsync(raw.fileno())
        os.replace(temporary, target)
        temporary = None
        _sync_folder(target.parent)
    except BaseException as error:
        if temporary is not None:
            with contextlib.suppress(OSError):
                os.unlink(temporary)
        if isinstance(error, OSError) and not isinstance(error, WriteError):
            raise _write_error(path, error) from error
        raise


def write_bytes(path, data: bytes) -> Path:
    """`data` into `path` through `replacing`. Returns the path."""
    with replacing(path) as f:
        f.write(data)
    return Path(path)


def write_together(files: dict[Path, bytes]) -> None:
    """Several files written as one (a run's table, report and plot): each to a temporary beside it
    and flushed to the disk first, then all renamed into place one after another with Ctrl-C held
    back until the last is in (on the main thread), so that an interrupt leaves either every file
    as it was or every file new, never a mix of two runs' (`bvhlab animate`: an interrupt while the
    plot was drawn left the new CSV and JSON beside the old plot). An error before the renames
    removes the temporaries and leaves every file as it was; one during them (a rename refused)
    leaves the files before it new and those after it old, and names the file refused."""
    staged: list[tuple[Path, Path]] = []
    current = Path()
    try:
        for path, data in files.items():
            current = Path(path)
            target = _target(current)
            temporary, fd = _create_temporary(target)
            staged.append((temporary, target))
            with os.fdopen(fd, "wb") as f:
                f.write(data)
                f.flush()
                os.fsync(f.fileno())
        folders = {target.parent for _, target in staged}
        with interrupts_held():
            for temporary, target in staged:
                current = target
                os.replace(temporary, target)
        staged.clear()
        for folder in folders:
            _sync_folder(folder)
    except BaseException as error:
        for temporary, _ in staged:
            with contextlib.suppress(OSError):
                os.unlink(temporary)
        if isinstance(error, OSError) and not isinstance(error, WriteError):
            raise _write_error(current, error) from error
        raise


@contextlib.contextmanager
def staged_folder(folder: Path) -> Iterator[Path]:
    """A new hidden folder inside `folder` for a command that writes many files over minutes
    (`bvhlab compare`: tables, charts, renders): when the block ends without an error its files
    are moved into `folder` together (with Ctrl-C held, as write_together renames), each replacing
    the file of its name there; after an error or a Ctrl-C it is removed and `folder` is as it
    was (an interrupt left the new tables beside the old charts)."""
    folder = Path(folder)
    stage = Path(tempfile.mkdtemp(prefix=".staged-", dir=folder))
    try:
        try:
            yield stage
        except WriteError as error:  # named by the file it was to become
            staged = Path(error.filename or "")
            if staged.is_relative_to(stage):
                raise WriteError(
                    error.errno or 0, error.strerror or "", str(folder / staged.relative_to(stage))
                ) from None
            raise
        names = sorted(p.relative_to(stage) for p in stage.rglob("*") if p.is_file() and not p.is_symlink())
        targets = []
        for name in names:
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
            targets.append(_target(folder / name))  # a folder or FIFO of that name: refused before any move
        with interrupts_held():
            for name, target in zip(names, targets):
                os.replace(stage / name, target)
        _sync_folder(folder)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


@contextlib.contextmanager
def interrupts_held() -> Iterator[None]:
    """Ctrl-C (SIGINT) held back inside and handed, after it, to the handler that was there before:
    Python's (KeyboardInterrupt), another callable, or the default action. Nothing is held where
    SIGINT is ignored (a background job's) or handled outside Python, or off the main thread
    (which never receives it)."""
    previous = signal.getsignal(signal.SIGINT)
    if (
        threading.current_thread() is not threading.main_thread()
        or previous is None  # a handler installed from C: left alone
        or previous == signal.SIG_IGN
    ):
        yield
        return
    came: list[bool] = []
    signal.signal(signal.SIGINT, lambda *_: came.append(True))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if came:
            deliver_interrupt(previous)


def deliver_interrupt(handler) -> None:
    """A Ctrl-C held back, handed to `handler` (what signal.getsignal(SIGINT) gave): the default
    action, or a Python callable (Python's own raises KeyboardInterrupt)."""
    if handler == signal.SIG_DFL:
        os.kill(os.getpid(), signal.SIGINT)
    elif callable(handler):
        handler(signal.SIGINT, None)


def write_text(path, text: str) -> Path:
    """`text` (UTF-8, newlines as given) into `path` through `replacing`. Returns the path."""
    with replacing(path, text=True) as f:
        f.write(text)
    return Path(path)
