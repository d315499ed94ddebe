"""One writer per output folder: `bvhlab compare` holds a lock on its --out folder while it runs,
so a second run into the same folder is refused at once, naming the run that holds it, instead of
the two leaving a mix of both runs' tables and figures (issue 39).

The lock is an advisory `flock` on a hidden file in the folder. The kernel releases it when the
holder ends, however it ends (a crash or SIGKILL leaves no stale lock, only at worst the empty
file, which the next run takes over)."""

from __future__ import annotations

import contextlib
import fcntl
import os
import socket
import time
from collections.abc import Iterator
from pathlib import Path

from ._atomic import WriteError

LOCK_NAME = ".bvhlab.lock"


class FolderBusy(RuntimeError):
    """The folder is held by another writer; the message names it."""


def _open_locked(path: Path) -> int | None:
    """A descriptor of `path` locked by this process, or None when another process holds it. A
    holder removes the file before it lets go, so a lock taken on a file that is no longer at
    `path` is a stale one: try again on the new file."""
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            return None
        except BaseException:
            os.close(fd)
            raise
        try:
            same = os.path.samestat(os.fstat(fd), os.stat(path))
        except FileNotFoundError:
            same = False
        if same:
            return fd
        os.close(fd)


def _describe_holder(path: Path) -> str:
    try:
        holder = path.read_text(encoding="utf-8", errors="replace").strip()
    except OSError:
        holder = ""
    return holder or "a process that did not say which"


def _say_holder(fd: int, what: str) -> None:
    """Who holds the lock, for the message of a run that is refused. Best effort: on a full disk the
    lock still holds, only unnamed."""
    started = time.strftime("%Y-%m-%d %H:%M:%S")
    text = f"{what}, pid {os.getpid()} on {socket.gethostname()}, started {started}\n".encode()
    with contextlib.suppress(OSError):
        os.ftruncate(fd, 0)
        os.pwrite(fd, text, 0)


@contextlib.contextmanager
def folder_lock(folder: Path, what: str) -> Iterator[None]:
    """Hold `folder` (which must exist) for the `with` block; FolderBusy at once if another process
    holds it. `what` says who holds it (e.g. "bvhlab compare") in the message others get."""
    path = Path(folder) / LOCK_NAME
    try:
        fd = _open_locked(path)
    except OSError as e:  # a read-only or full folder: name the file, as every write does
        raise WriteError(e.errno or 0, e.strerror or str(e), str(path)) from None
    if fd is None:
        raise FolderBusy(
            f"{folder} is being written by another run ({_describe_holder(path)}); "
            f"wait for it to finish or choose another folder"
        )
    try:
        _say_holder(fd, what)
        yield
    finally:
        with contextlib.suppress(OSError):
            os.unlink(path)  # while still held, so no one locks the old file after this
        os.close(fd)
