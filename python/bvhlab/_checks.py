"""Argument checks with messages that say what was expected and what came instead."""

from __future__ import annotations

import contextlib
import math
import numbers
import os
import secrets
from pathlib import Path

import numpy as np


def float32_array(name: str, value, trailing_shape: tuple[int, ...]) -> np.ndarray:
    """Return `value` itself (no copy) if it is a C-contiguous float32 array of shape (N, *trailing_shape).

    Wrong types and dtypes raise TypeError, wrong shapes or layouts ValueError: silently copying a
    float64 array would hide a doubling of memory and time from the caller.
    """
    want = "(" + ", ".join(["N", *map(str, trailing_shape)]) + ("," if not trailing_shape else "") + ")"
    if not isinstance(value, np.ndarray):
        raise TypeError(f"{name} must be a numpy float32 array of shape {want}, got {type(value).__name__}")
    if isinstance(value, np.ma.MaskedArray):  # its mask would be dropped: masked triangles built and hit
        raise TypeError(
            f"{name} is a masked array, whose mask bvhlab would ignore: pass {name}.compressed() rows "
            f"or {name}.filled(...) instead"
        )
    if value.dtype != np.float32:
        raise TypeError(
            f"{name} must have dtype float32, got {value.dtype} (convert explicitly with {name}.astype(np.float32))"
        )
    if value.ndim != 1 + len(trailing_shape) or value.shape[1:] != trailing_shape:
        raise ValueError(f"{name} must have shape {want}, got {value.shape}")
    if not value.flags.c_contiguous:
        raise ValueError(f"{name} must be C-contiguous (np.ascontiguousarray({name}) makes a copy)")
    return value


def flag(name: str, value) -> bool:
    """True or False (numpy's np.True_ and np.False_ too); anything else a TypeError, not truthiness."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {value!r} ({type(value).__name__})")
    return bool(value)


def integer(name: str, value, lo: float, hi: float) -> int:
    """An int in [lo, hi]; bools and floats are rejected rather than truncated."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an integer, got {type(value).__name__}")
    value = int(value)
    if not lo <= value <= hi:
        raise ValueError(f"{name} must be between {lo} and {hi}, got {value}")
    return value


#: The deepest depth a range may name: a tree's depths are below 256.
MAX_DEPTH = 255


def depth_range(depth_min, depth_max) -> tuple[int, int]:
    """A range of tree depths for boxes (Bvh.boxes, InstancedBvh.tlas_boxes): depth_max None is
    every depth; a depth_min above depth_max raises ValueError, as the overlay's range does (it gave
    no boxes, silently)."""
    lo = integer("depth_min", depth_min, 0, MAX_DEPTH)
    hi = MAX_DEPTH if depth_max is None else integer("depth_max", depth_max, 0, MAX_DEPTH)
    if lo > hi:
        raise ValueError(f"depth_min {lo} is greater than depth_max {hi}")
    return lo, hi


def power_of_two(name: str, value, hi: int) -> int:
    """An int that is a power of two from 1 to hi."""
    value = integer(name, value, 1, hi)
    if value & (value - 1):
        raise ValueError(f"{name} must be a power of two from 1 to {hi}, got {value}")
    return value


def choice(name: str, value, options: tuple[str, ...]) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a string, one of {', '.join(options)}; got {type(value).__name__}")
    if value not in options:
        raise ValueError(f"unknown {name} '{value}'; expected one of: {', '.join(options)}")
    return value


def real(name: str, value, lo: float = -math.inf, hi: float = math.inf) -> float:
    """A real number (int or float, not bool; a numpy array of no dimensions too) in [lo, hi]; NaN
    is rejected."""
    if type(value) is np.ndarray and value.ndim == 0 and value.dtype.kind in "iuf":  # not a masked array
        value = value.item()
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, got {type(value).__name__}")
    try:
        value = float(value)
    except OverflowError:  # an integer beyond float's range: ±inf, as a float literal past it reads
        value = math.inf if value > 0 else -math.inf
    if math.isnan(value):
        raise ValueError(f"{name} must be a number, got NaN")
    if not lo <= value <= hi:
        raise ValueError(f"{name} must be {_range_text(lo, hi)}, got {value}")
    return value


def _range_text(lo: float, hi: float) -> str:
    """'between 0 and 1', 'at least 0', 'at most 1' (no infinite bound written out; whole numbers
    whole, as 4294967295)."""

    def text(x: float) -> str:
        return str(int(x)) if float(x).is_integer() else f"{x:g}"

    if math.isinf(lo) and math.isinf(hi):
        return "finite"
    if math.isinf(hi):
        return f"at least {text(lo)}"
    if math.isinf(lo):
        return f"at most {text(hi)}"
    return f"between {text(lo)} and {text(hi)}"


#: The largest finite float32 (numpy.finfo(numpy.float32).max) and the smallest normal one
#: (numpy.finfo(numpy.float32).tiny).
FLOAT32_MAX = 3.4028234663852886e38
FLOAT32_TINY = 1.1754943508222875e-38


def setting(name: str, value, lo: float = -math.inf, hi: float = math.inf, zero_ok: bool = True) -> float:
    """real(...) for a float32 field of a core config struct: a finite number beyond float32's range
    is refused too (1e300 would arrive as inf and be reported as "got inf"), and so is one other than
    0 that float32 holds only as 0 or a denormal (sbvh_alpha 1e-46 arrived as 0 and was taken; a
    camera aspect of 1e-50 as 0, "the image's"). Ray limits (tmin, tmax) stay real(): beyond
    float32's range is inf there, which is what such a limit means. `zero_ok` False: the message
    does not offer 0 (restructure_share 1e-50 was told "must be 0 or ...", and 0 is refused)."""
    value = real(name, value, lo, hi)
    if math.isfinite(value) and abs(value) > FLOAT32_MAX:
        raise ValueError(f"{name} must be within float32's range (±{FLOAT32_MAX:.7g}), got {value:g}")
    if value != 0 and abs(float(np.float32(value))) < FLOAT32_TINY:
        raise ValueError(
            f"{name} must be {'0 or ' if zero_ok else ''}of magnitude {FLOAT32_TINY:.7g} to {FLOAT32_MAX:.7g} "
            f"(a normal float32), got {value:g}"
        )
    return value


def input_file(path: Path, what: str, error: type[Exception]) -> None:
    """Refuses, before it is opened, a `path` that exists and is not a regular file: a folder, or
    a FIFO, device or socket (opening a FIFO blocks until someone writes to it). A missing file is
    left to the reader (FileNotFoundError). `what` names the file expected ("scene file"),
    `error` is the reader's own error type."""
    if path.is_dir():
        raise error(f"{path} is a folder, not a {what}")
    if path.exists() and not path.is_file():
        raise error(f"{path} is not a regular file (a FIFO, device or socket), not a {what}")


class OutputPathError(OSError, ValueError):
    """An output path that cannot be written as given (a folder, under a file, a wrong suffix).
    Both an OSError (it is about the file system) and a ValueError (it is a bad argument)."""


def output_file(path, suffixes: tuple[str, ...], what: str) -> Path:
    """`path` as a Path, checked before any work is done: not an existing folder, no existing file
    where a parent folder must be, and a name ending in one of `suffixes` (the file is written
    exactly where asked, never renamed). Raises OutputPathError saying what is wrong."""
    path = Path(path)
    if path.is_dir():
        raise OutputPathError(
            f"{path} is a folder; give a file name for the {what}, e.g. {path / ('out' + suffixes[0])}"
        )
    if path.name.lower() in suffixes:  # ".png" alone is a hidden file with no suffix to Path
        example = path.with_name("out" + path.name)
        raise OutputPathError(f"{path}: the file name has no stem, only the suffix; name the file, e.g. {example}")
    if path.suffix.lower() not in suffixes:
        article = "an" if what[0] in "aeiou" else "a"  # "an inspection file"
        raise OutputPathError(
            f"{path}: {article} {what} is written as {' or '.join(suffixes)}; name the file so "
            f"(e.g. {path.with_name(path.stem + suffixes[0])}), it is not renamed for you"
        )
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise OutputPathError(f"{path}: {parent} is a file, not a folder")
            check_writable(parent, path)
            break
    return path


def check_writable(folder: Path, target: Path) -> None:
    """Whether a file can be made in `folder` (the nearest existing folder of the output `target`),
    found by making one and deleting it: permissions say nothing of read-only mounts and /proc or
    /sys, whose refusal came only after the work (a whole animation experiment). Raises
    OutputPathError naming the target."""
    for _ in range(16):  # a name taken: another (mkstemp would retry for hours on Windows' access denied)
        probe = folder / f".bvhlab-write-check-{secrets.token_hex(8)}"
        try:
            handle = os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
        except FileExistsError:
            continue
        except OSError as e:
            raise OutputPathError(
                f"cannot write {target}: {folder} does not take new files ({e.strerror or e})"
            ) from None
        os.close(handle)
        with contextlib.suppress(OSError):  # an append-only folder keeps it: harmless, hidden
            os.unlink(probe)
        return
