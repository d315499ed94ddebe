"""JSON that every parser reads: the figures bvhlab writes may be NaN (a timing not taken) or
infinite (a ray's distance where it hits nothing), which Python's json writes as the tokens NaN and
Infinity that strict parsers refuse; here they are null."""

from __future__ import annotations

import json
import math
from typing import Any


def plain(value: Any) -> Any:
    """`value` with every float that is not finite (NaN, ±inf, numpy's too) replaced by None, in
    dicts, lists, tuples and numpy arrays (made lists) at any depth."""
    if isinstance(value, float):  # numpy's float64 is a float
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if hasattr(value, "dtype") and getattr(value, "shape", None) == ():  # a numpy scalar
        return plain(value.item())
    if hasattr(value, "dtype") and hasattr(value, "tolist"):  # a numpy array: a list (of lists)
        return plain(value.tolist())
    return value


def dumps(value: Any, **kwargs) -> str:
    """json.dumps of plain(value), refusing anything not finite that plain() did not reach."""
    return json.dumps(plain(value), allow_nan=False, **kwargs)
