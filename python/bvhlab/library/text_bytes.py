"""The bytes of a text mesh file (OBJ, ASCII STL and PLY) as UTF-8. Windows' Notepad ("Unicode")
and PowerShell 5's `>` save text as UTF-16 with a byte-order mark, in which every other byte of
an ASCII file is NUL: read as UTF-8, such a file has no statements at all ("0 faces")."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np

from .._npz import SceneFileError

_UTF16_MARKS = {b"\xff\xfe": "utf-16-le", b"\xfe\xff": "utf-16-be"}


def utf8_bytes(path: Path, data: bytes) -> bytes:
    """`data` as UTF-8: a UTF-16 file (by its byte-order mark) decoded, a UTF-8 byte-order mark
    dropped (a PLY saved by Notepad as "UTF-8 with BOM" was "not a PLY file"); anything else as it
    is."""
    if data.startswith(b"\xef\xbb\xbf"):
        return data[3:]
    for mark, codec in _UTF16_MARKS.items():
        if data.startswith(mark):
            try:
                return data[len(mark) :].decode(codec).encode("utf-8")
            except UnicodeDecodeError as e:
                raise SceneFileError(
                    f"{path}: starts with a UTF-16 byte-order mark but is not UTF-16 "
                    f"({e.reason} at byte {e.start + len(mark)})"
                ) from None
    return data


def refuse_nul(path: Path, data: bytes, kind: str) -> None:
    """A text file has no NUL bytes: one that has is UTF-16 without its mark, or not `kind` text."""
    at = data.find(b"\x00")
    if at >= 0:
        raise SceneFileError(
            f"{path}: a NUL byte at byte {at}, which {kind} text has not (UTF-16 without a byte-order mark, "
            "or not a text file? save it as UTF-8)"
        )


#: What Python's float() and int() read and a number in a mesh file is not: digit separators
#: ("1_0" read as 10) and digits of other scripts ("１", "١" read as 1). numpy's fast parse refuses
#: both; the slower paths that parse word by word must too.
_NOT_IN_A_NUMBER = re.compile(rb"_|[^\x00-\x7f]")


def refuse_odd_numbers(path: Path, text: bytes, where: str) -> None:
    """Refuses `text` (the words of numbers) holding a digit separator or a non-ASCII character."""
    found = _NOT_IN_A_NUMBER.search(text)
    if found:
        start = max(text.rfind(space, 0, found.start()) for space in (b" ", b"\t", b"\n", b"\r")) + 1
        word = text[start : found.end() + 8].split()[0].decode("utf-8", errors="replace")
        raise SceneFileError(f"{path}: {where}: {word!r} is not a number (ASCII digits, no '_')")


def numbers(text: str | bytes, dtype) -> np.ndarray | None:
    """The numbers of `text`, separated by any whitespace, parsed in C (as Python's float() and
    int() read them, but for refuse_odd_numbers' words); None if a word is not a number."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)  # numpy < 2.x: a partial read warns
        try:
            return np.fromstring(text, dtype=dtype, sep=" ")
        except (ValueError, DeprecationWarning):
            return None
