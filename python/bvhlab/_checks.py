"""Argument checks with messages that say what was expected and what came instead."""
from __future__ import annotations

import numbers

import numpy as np


def float32_array(name: str, value, trailing_shape: tuple[int, ...]) -> np.ndarray:
    """Return `value` itself (no copy) if it is a C-contiguous float32 array of shape (N, *trailing_shape).

    Wrong types and dtypes raise TypeError, wrong shapes or layouts ValueError: silently copying a
    float64 array would hide a doubling of memory and time from the caller.
    """
    want = "(N, " + ", ".join(str(d) for d in trailing_shape) + ")"
    if not isinstance(value, np.ndarray):
        raise TypeError(f"{name} must be a numpy float32 array of shape {want}, got {type(value).__name__}")
    if value.dtype != np.float32:
        raise TypeError(f"{name} must have dtype float32, got {value.dtype} "
                        f"(convert explicitly with {name}.astype(np.float32))")
    if value.ndim != 1 + len(trailing_shape) or value.shape[1:] != trailing_shape:
        raise ValueError(f"{name} must have shape {want}, got {value.shape}")
    if not value.flags.c_contiguous:
        raise ValueError(f"{name} must be C-contiguous (np.ascontiguousarray({name}) makes a copy)")
    return value


def integer(name: str, value, lo: int, hi: int) -> int:
    """An int in [lo, hi]; bools and floats are rejected rather than truncated."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an integer, got {type(value).__name__}")
    value = int(value)
    if not lo <= value <= hi:
        raise ValueError(f"{name} must be between {lo} and {hi}, got {value}")
    return value


def choice(name: str, value, options: tuple[str, ...]) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a string, one of {', '.join(options)}; got {type(value).__name__}")
    if value not in options:
        raise ValueError(f"unknown {name} '{value}'; expected one of: {', '.join(options)}")
    return value
