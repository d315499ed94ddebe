"""Reading an `.npz` that may be hostile: every member's `.npy` header is read and checked (dtype,
shape, and the size the zip directory declares) before any array data is, so a small file cannot
make the reader allocate gigabytes (a 3.85 MB file used to expand to 3.9 GB before the first check),
and every failure is one SceneFileError naming the file and the problem. Writing one: whole or not
at all (`write_npz`)."""

from __future__ import annotations

import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import _checks
from ._atomic import replacing

#: A file may expand to at most this many times its size once the arrays exceed MIN_CHECKED_BYTES.
#: Real geometry deflates by 1.1-3x; only crafted (or absurdly regular) data compresses 100x.
MAX_EXPANSION = 100.0
MIN_CHECKED_BYTES = 64 << 20


class SceneFileError(ValueError):
    """A scene file that cannot be read: not an .npz, a member missing or of the wrong dtype or
    shape, sizes that do not add up. The message names the file."""


@dataclass(frozen=True)
class Member:
    """What an array must look like: dtype kinds ('f' float, 'iu' integer) and a shape in which
    None matches any length."""

    kinds: str
    shape: tuple


def read_npz(
    path: Path,
    members: dict[str, Member],
    optional: tuple[str, ...] = (),
    same_length: tuple[tuple[str, str], ...] = (),
    max_expansion: float = MAX_EXPANSION,
) -> dict[str, np.ndarray]:
    """The arrays named in `members` (those in `optional` may be absent), checked as described above;
    each pair in `same_length` must agree in their first dimension."""
    _checks.input_file(path, "scene file", SceneFileError)
    try:
        with zipfile.ZipFile(path) as archive:
            headers = {name: _header(path, archive, name) for name in members if _has(archive, name)}
            _check_members(path, members, optional, headers)
            _check_lengths(path, headers, same_length)
            _check_total_size(path, headers, max_expansion)
            return {name: _read(path, archive, name, header) for name, header in headers.items()}
    except zipfile.BadZipFile as e:
        if "CRC" in str(e):  # a member read whole whose checksum does not match
            raise SceneFileError(f"{path} is damaged ({e})") from None
        raise SceneFileError(f"{path} is not an .npz file (not a zip archive, or a truncated one)") from None
    except zlib.error as e:  # a member's compressed data damaged
        raise SceneFileError(f"{path} is damaged (its compressed data cannot be read: {e})") from None
    except (OSError, EOFError, zipfile.LargeZipFile, NotImplementedError) as e:
        if isinstance(e, (FileNotFoundError, PermissionError)):
            raise
        raise SceneFileError(f"{path} cannot be read: {e}") from None


def write_npz(path: Path, arrays: dict[str, np.ndarray]) -> Path:
    """`arrays` as a compressed `.npz` at exactly `path` (no suffix added, no pickled objects); an
    old file is replaced only by a complete new one (bvhlab._atomic). Returns the path."""
    # the archive closed by its own `with` (np.savez_compressed left its ZipFile open when Ctrl-C
    # came mid-write, and its __del__ later wrote into the file `replacing` had closed: "Exception
    # ignored ... seek of closed file" after "interrupted"); the members as savez_compressed makes them
    with (
        replacing(path) as f,  # a file object: no suffix added
        zipfile.ZipFile(f, "w", zipfile.ZIP_DEFLATED, allowZip64=True) as archive,
    ):
        for name, array in arrays.items():
            with archive.open(name + ".npy", "w", force_zip64=True) as member:
                np.lib.format.write_array(member, np.asanyarray(array), allow_pickle=False)
    return path


def _has(archive: zipfile.ZipFile, name: str) -> bool:
    return name + ".npy" in archive.NameToInfo


@dataclass(frozen=True)
class _Header:
    dtype: np.dtype
    shape: tuple
    fortran_order: bool
    data_bytes: int  # what the zip directory says the array data takes


def _header(path: Path, archive: zipfile.ZipFile, name: str) -> _Header:
    info = archive.getinfo(name + ".npy")
    with archive.open(info) as f:
        try:
            version = np.lib.format.read_magic(f)
            reader = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            shape, fortran_order, dtype = reader(f)
        except ValueError as e:
            raise SceneFileError(f"{path}: '{name}' is not a numpy array ({e})") from None
        header_bytes = f.tell()
    return _Header(dtype, shape, fortran_order, info.file_size - header_bytes)


def _check_members(path: Path, members: dict[str, Member], optional: tuple[str, ...], headers: dict) -> None:
    missing = [name for name in members if name not in headers and name not in optional]
    if missing:
        raise SceneFileError(f"{path} has no {', '.join(repr(m) for m in missing)}: not a bvhlab scene file")
    for name, header in headers.items():
        want = members[name]
        if header.dtype.hasobject or header.dtype.kind not in want.kinds or header.dtype.shape:
            raise SceneFileError(
                f"{path}: '{name}' has dtype {header.dtype}; expected "
                f"{'a float' if want.kinds == 'f' else 'an integer'} type"
            )
        if len(header.shape) != len(want.shape) or any(
            w is not None and w != h for w, h in zip(want.shape, header.shape)
        ):
            expected = (
                "("
                + ", ".join("N" if w is None else str(w) for w in want.shape)
                + ("," if len(want.shape) == 1 else "")
                + ")"
            )
            raise SceneFileError(f"{path}: '{name}' has shape {header.shape}; expected {expected}")
        need = int(np.prod(header.shape, dtype=np.int64)) * header.dtype.itemsize
        if need != header.data_bytes:
            raise SceneFileError(
                f"{path}: '{name}' declares shape {header.shape} ({need} bytes) but its data "
                f"takes {header.data_bytes} bytes"
            )


def _check_lengths(path: Path, headers: dict, same_length: tuple[tuple[str, str], ...]) -> None:
    for a, b in same_length:
        if a in headers and b in headers and headers[a].shape[0] != headers[b].shape[0]:
            raise SceneFileError(f"{path}: '{a}' has {headers[a].shape[0]} rows but '{b}' has {headers[b].shape[0]}")


def _check_total_size(path: Path, headers: dict, max_expansion: float) -> None:
    total = sum(h.data_bytes for h in headers.values())
    size = path.stat().st_size
    if total > MIN_CHECKED_BYTES and total > max_expansion * size:
        raise SceneFileError(
            f"{path}: its arrays would take {total / 2**20:.0f} MiB, {total / size:.0f} times "
            f"the file's {size / 2**20:.1f} MiB (at most {max_expansion:g} times is read; "
            f"pass a larger max_expansion to Scene.load if you trust the file)"
        )


def _read(path: Path, archive: zipfile.ZipFile, name: str, header: _Header) -> np.ndarray:
    with archive.open(name + ".npy") as f:
        try:
            return np.lib.format.read_array(f, allow_pickle=False)
        except ValueError as e:
            raise SceneFileError(f"{path}: '{name}' cannot be read ({e})") from None
