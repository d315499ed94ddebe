"""STL's triangles (3D Systems, "StereoLithography Interface Specification", 1988), binary or
ASCII. A file is binary when its size is what its triangle count says (84 + 50 per triangle),
whatever its first bytes (binary headers often start with "solid"); else ASCII if it starts with
"solid" in any case (after a UTF-8 byte-order mark or spaces), each facet's three `vertex x y z`
statements read wherever its lines break (STL is whitespace-separated: a facet may be one line).
Anything else is refused, a facet of other than three vertices too."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .._npz import SceneFileError
from .text_bytes import utf8_bytes

_HEADER, _TRIANGLE = 84, 50
_BINARY = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
# one way only to split a number's digits (`\d+\.?\d*` split "111" three ways, and three numbers
# a vertex: a 557-byte file of 160-digit numbers took 38 s to refuse, n^4)
_NUMBER = rb"([-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf)\w*)"
# words between whitespace, outside the `solid name` and `endsolid name` lines (a name is free
# text to its line's end and may say "vertex" or "facet": "solid vertex colors")
# (three numbers and then the next vertex, or the loop's or facet's end: `vertex 0 0 0 7` is not one)
_VERTEX = re.compile(
    rb"(?<!\S)vertex\s+" + rb"\s+".join([_NUMBER] * 3) + rb"(?=\s+(?:vertex|endloop|endfacet)(?!\S)|\s*$)",
    re.IGNORECASE,
)
_VERTEX_WORD = re.compile(rb"(?<!\S)vertex(?!\S)", re.IGNORECASE)
_ENDFACET = re.compile(rb"(?<!\S)endfacet(?!\S)", re.IGNORECASE)
# a solid's line, from its start. One way only to split its leading blanks around a byte-order mark:
# `[ \t]*(?:BOM)?[ \t]*` tried every split of a run of blanks not followed by "solid" (a 20 KB line
# of spaces took 6.7 s, 4 MB hours: a helper's audit)
_SOLID_TEXT = rb"[ \t]*(?:\xef\xbb\xbf[ \t]*)?(?:end)?solid\b[^\r\n]*"
_SOLID_LINE = re.compile(rb"(?mi)^" + _SOLID_TEXT)
# a file written on one line ("solid t facet normal ... endsolid t"): a name of one word, if any
_SOLID_WORDS = re.compile(rb"(?i)(?<!\S)(?:end)?solid(?:[ \t]+(?!facet(?!\S))[^\s]+)?(?!\S)")


def read_stl(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """float64 (3T, 3) positions and int64 (T, 3) triangles (every triangle its own three) of the
    STL file at `path`."""
    data = path.read_bytes()
    count = int.from_bytes(data[80:84], "little") if len(data) >= _HEADER else -1
    binary = count >= 0 and len(data) == _HEADER + _TRIANGLE * count
    text = b"" if binary else utf8_bytes(path, data)  # an ASCII STL saved as UTF-16
    if binary:
        vertices = np.frombuffer(data, _BINARY, count, _HEADER)["vertices"].astype(np.float64).reshape(-1, 3)
    elif text.lstrip(b"\xef\xbb\xbf \t\r\n")[:5].lower() == b"solid" and (written := _as_written(text)) is not None:
        vertices = written
    elif text.lstrip(b"\xef\xbb\xbf \t\r\n")[:5].lower() == b"solid":
        # a solid's line that ends a facet held facets ("solid t facet ... endfacet", the whole file
        # or its first facets on one line): then only a name of one word is the solid's
        held = any(_ENDFACET.search(line) for line in _SOLID_LINE.findall(text))
        facets = (_SOLID_WORDS if held else _SOLID_LINE).sub(b"", text)
        found = _VERTEX.findall(facets)
        if len(found) != len(_VERTEX_WORD.findall(facets)):  # a vertex of other than three numbers
            raise SceneFileError(f"{path}: a vertex line is not 'vertex x y z' (three numbers)")
        if not found and count >= 0:
            raise SceneFileError(
                f"{path}: no facets: starts as ASCII STL but has no vertex lines, and as binary STL its header "
                f"declares {count} triangles ({_HEADER + _TRIANGLE * count} bytes) for its {len(data)} bytes"
            )
        _check_facets(path, facets)
        try:
            vertices = np.array(found, dtype=np.float64).reshape(-1, 3)
        except ValueError:  # a word the pattern takes for nan or inf ("nanx", "infinit"): a review's
            raise SceneFileError(f"{path}: a vertex line is not 'vertex x y z' (three numbers)") from None
    elif count >= 0:
        raise SceneFileError(
            f"{path}: the header declares {count} triangles ({_HEADER + _TRIANGLE * count} bytes), "
            f"the file has {len(data)} bytes ({'truncated?' if len(data) < _HEADER + _TRIANGLE * count else 'more'}), "
            "and it is not ASCII STL"
        )
    else:
        raise SceneFileError(f"{path}: {len(data)} bytes: neither binary STL (84 at least) nor ASCII")
    return vertices, np.arange(len(vertices), dtype=np.int64).reshape(-1, 3)


# The layout STL writers use, facet by facet: 21 words, the numbers' places None.
_FACET_WORDS: tuple[bytes | None, ...] = (b"facet", b"normal", None, None, None, b"outer", b"loop")
_FACET_WORDS += (b"vertex", None, None, None) * 3 + (b"endloop", b"endfacet")
_KEYWORDS = [(k, word) for k, word in enumerate(_FACET_WORDS) if word is not None]
_NUMBERS = [k for k, word in enumerate(_FACET_WORDS) if word is None]  # the normal's three, then the vertices'
# a solid's first and last lines, as _SOLID_LINE takes them (its line break included in the first)
_SOLID_START = re.compile(_SOLID_TEXT + rb"\r?\n", re.IGNORECASE)
_SOLID_END = re.compile(_SOLID_TEXT + rb"\r?", re.IGNORECASE)
_NOT_SPACE = re.compile(rb"\S")
_PIECE = 1 << 22  # bytes of facets split into words at a time
_LONGEST = 64  # bytes of a number read by the layout's path (longer ones: the exact path's checks)


def _as_written(text: bytes) -> np.ndarray | None:
    """The vertices of an ASCII STL laid out as its writers write it, read a piece at a time by
    splitting words (the exact path's patterns took 31 s for a million facets and ~7× the file's
    size in memory): one or more solids (CAD tools write a body a solid), each a `solid` line that
    holds no facet, facets of exactly the 21 words of _FACET_WORDS in lower or upper case (any
    whitespace between them) and an `endsolid` line, nothing after the last. None for any other
    file, which the exact path then reads or refuses with its message: the numbers are those the
    exact path takes (Python's float reads "1_0" too, and numpy drops a word's trailing NUL bytes:
    facets with an underscore or a NUL are left to it), each `endfacet` must end its word, so both
    give the same vertices, bit for bit, or this path gives None (a review's cases:
    `endfacetendsolid`, `endfacetfacet` where a piece ends, a vertex after `endsolid`,
    `vertex 1\\0 2 3`)."""
    solids, at = [], 0
    while True:
        # this solid ends at the first `endsolid` after its `solid` line (a name that says
        # endsolid: its facets fail the layout's words, and the exact path reads the file)
        line = text.find(b"\n", at) + 1
        ends = [e for e in (text.find(b"endsolid", line), text.find(b"ENDSOLID", line)) if e >= 0]
        if line == 0 or not ends:
            return None
        tail = min(ends)
        after = text.find(b"\n", tail)
        after = len(text) if after < 0 else after
        vertices = _solid_as_written(text, at, line, tail, after)
        if vertices is None:
            return None
        solids.append(vertices)
        following = _NOT_SPACE.search(text, after)  # past the blank lines between the solids
        if following is None:
            return np.concatenate(solids) if len(solids) > 1 else solids[0]
        at = text.rfind(b"\n", 0, following.start()) + 1  # the next solid's line, from its start


def _solid_as_written(text: bytes, at: int, line: int, tail: int, after: int) -> np.ndarray | None:
    """_as_written's reading of one solid: its `solid` line text[at:line], its facets
    text[line:tail], its `endsolid` line text[tail:after]."""
    # the lines the exact path takes for a solid's (_SOLID_LINE), and no others: a name is free
    # text, and one that says `vertex` after a form feed or a lone CR was read here and refused
    # there (the review's)
    end_line = text.rfind(b"\n", 0, tail) + 1
    if not _SOLID_START.fullmatch(text, at, line) or not _SOLID_END.fullmatch(text, end_line, after):
        return None
    if b"facet" in text[at:line].lower() or b"facet" in text[tail:after].lower():
        return None
    if text.find(b"_", line, tail) >= 0 or text.find(b"\0", line, tail) >= 0:
        return None
    pieces, at = [], line
    while True:
        limit = min(at + _PIECE, tail)
        cut = max(text.rfind(b"endfacet", at, limit), text.rfind(b"ENDFACET", at, limit))
        if cut < 0:
            break
        words = text[at : cut + len(b"endfacet")].split()
        at = cut + len(b"endfacet")
        if not text[at : at + 1].isspace():  # `endfacetfacet`: not the word endfacet
            return None
        if len(words) % len(_FACET_WORDS) or max(map(len, words)) > _LONGEST:
            return None
        grid = np.array(words).reshape(-1, len(_FACET_WORDS))
        for k, word in _KEYWORDS:
            column = grid[:, k]
            if not any((column == w).all() for w in (word, word.upper())) and not (np.char.lower(column) == word).all():
                return None
        try:
            pieces.append(grid[:, _NUMBERS].astype(np.float64)[:, 3:].reshape(-1, 3))
        except ValueError:  # not a number (the normal's too: a word there is the exact path's to judge)
            return None
    if not pieces or text[at:tail].strip():
        return None
    return np.concatenate(pieces)


def _check_facets(path: Path, facets: bytes) -> None:
    """Every facet of an ASCII STL has three vertices and ends with `endfacet`: the vertices are
    read three to a triangle, so a facet of four and one of two made two triangles of parts of
    both, with no error."""
    ends = np.fromiter((m.start() for m in _ENDFACET.finditer(facets)), np.int64)
    starts = np.fromiter((m.start() for m in _VERTEX_WORD.finditer(facets)), np.int64)
    per_facet = np.bincount(np.searchsorted(ends, starts), minlength=len(ends) + 1)
    if per_facet[-1]:
        raise SceneFileError(f"{path}: {per_facet[-1]} vertex lines after the last endfacet (truncated?)")
    wrong = np.flatnonzero(per_facet[:-1] != 3)
    if len(wrong):
        k = int(wrong[0])
        raise SceneFileError(
            f"{path}: facet {k + 1} has {per_facet[k]} vertices, not three ({len(wrong)} such facet(s))"
        )
