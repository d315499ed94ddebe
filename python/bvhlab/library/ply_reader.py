"""PLY's geometry (Turk, "The PLY Polygon File Format", 1994): the `vertex` element's x, y, z and
the `face` element's vertex_indices (or vertex_index) lists, in ASCII or binary of either byte
order; every other element and property is read past. Faces of any size in one file (Blender's
binary export of a mesh of triangles and quads), triangulated by polygons.py. The header's counts
are the file's: a file that ends early or goes on after its last element is refused."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._npz import SceneFileError
from .ply_lists import Lists, ascii_element, binary_element
from .polygons import triangulate_runs
from .text_bytes import numbers, refuse_odd_numbers, utf8_bytes

#: PLY's scalar type names (both spellings) → numpy's.
_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}  # fmt: skip
_MAX_HEADER = 64 << 10  # the format sets no limit; real headers are < 1 KB


@dataclass
class _Property:
    name: str
    type: str  # numpy type of the value, or of a list's items
    count_type: str | None = None  # numpy type of a list's length; None: a scalar


@dataclass
class _Element:
    name: str
    count: int
    properties: list[_Property] = field(default_factory=list)


def read_ply(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """float64 (V, 3) positions and int64 (T, 3) triangles of the PLY file at `path`."""
    data = utf8_bytes(path, path.read_bytes())  # an ASCII PLY saved as UTF-16
    fmt, elements, start = _header(path, data)
    if fmt == "ascii":
        values = _read_ascii(path, data[start:], elements)
    else:
        values = _read_binary(path, data, start, elements, "<" if fmt == "binary_little_endian" else ">")
    vertex, face = values.get("vertex"), values.get("face")
    if vertex is None or not all(axis in vertex for axis in "xyz"):
        raise SceneFileError(f"{path}: no vertex element with x, y and z")
    positions = np.stack([np.asarray(vertex[axis], np.float64) for axis in "xyz"], axis=1)
    name = None if face is None else next((n for n in ("vertex_indices", "vertex_index") if n in face), None)
    if face is None or name is None:
        raise SceneFileError(f"{path}: no face element with vertex_indices")
    kind = next(p for e in elements if e.name == "face" for p in e.properties if p.name == name)
    if kind.count_type is None:
        raise SceneFileError(f"{path}: the face element's {name} must be a list of vertex indices")
    lists = face[name]
    if kind.type[0] == "f" and not (np.floor(lists.items) == lists.items).all():  # indices written as floats (rare)
        raise SceneFileError(f"{path}: the face element's {name} holds numbers that are not indices")
    return positions, _triangles(path, lists, positions)


# the elements and properties the reader reads (read_ply)
_READ = {"vertex": ("x", "y", "z"), "face": ("vertex_indices", "vertex_index")}


def _header(path: Path, data: bytes) -> tuple[str, list[_Element], int]:
    # the line "end_header" (not the words in a comment)
    found = re.search(rb"(?:^|\n)[ \t]*end_header[ \t]*\r?(?:\n|$)", data[:_MAX_HEADER])
    if not re.match(rb"ply[ \t]*\r?\n", data):  # the magic line ("plyx" is not it)
        raise SceneFileError(f"{path}: not a PLY file (its first line is not 'ply')")
    if found is None:
        raise SceneFileError(f"{path}: no 'end_header' line in its first {_MAX_HEADER >> 10} KiB (not a PLY file?)")
    end, start = found.start(), found.end()
    fmt, elements = None, []
    for line in data[:end].decode("ascii", errors="replace").splitlines()[1:]:
        words = line.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        try:
            if words[0] == "format":
                if fmt is not None:  # the second replaced the first, then "truncated" (a helper's audit)
                    raise SceneFileError(f"{path}: two 'format' lines")
                if len(words) > 2 and float(words[2]) != 1.0:  # the only version; "2.0" was read as it
                    raise SceneFileError(f"{path}: PLY version {words[2]!r}; bvhlab reads version 1.0")
                fmt = words[1]
            elif words[0] == "element":
                elements.append(_Element(words[1], int(words[2])))
            elif words[0] == "property" and words[1] == "list":
                elements[-1].properties.append(_Property(words[4], _TYPES[words[3]], _TYPES[words[2]]))
            elif words[0] == "property":
                elements[-1].properties.append(_Property(words[2], _TYPES[words[1]]))
        except SceneFileError:
            raise
        except (IndexError, KeyError, ValueError):
            raise SceneFileError(f"{path}: header line {line.strip()!r} is not PLY") from None
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise SceneFileError(f"{path}: unknown PLY format {fmt!r}")
    # one vertex and one face element, and one of each property read from them: the reader keeps
    # them by name, and a second `element face` replaced the first's faces (of two declared, one
    # triangle read); names it does not read may repeat
    names = [e.name for e in elements]
    for e in elements:
        if e.name not in _READ:
            continue
        if names.count(e.name) > 1:
            raise SceneFileError(f"{path}: the header declares {names.count(e.name)} elements named {e.name!r}")
        props = [p.name for p in e.properties]
        for name in _READ[e.name]:
            if props.count(name) > 1:
                raise SceneFileError(
                    f"{path}: the {e.name} element declares {props.count(name)} properties named {name!r}"
                )
    for e in elements:  # a float length read "ends inside its face elements" (an ASCII one reads)
        for p in e.properties:
            if fmt != "ascii" and p.count_type is not None and np.dtype(p.count_type).kind not in "iu":
                raise SceneFileError(
                    f"{path}: the {e.name} element's list {p.name}: a binary list's length must have an integer type"
                )
    for e in elements:
        if e.count < 0 or e.count > len(data):  # every element takes at least a byte
            raise SceneFileError(f"{path}: the header declares {e.count} {e.name} elements for a {len(data)}-byte file")
    return fmt, elements, start


def _read_ascii(path: Path, body: bytes, elements: list[_Element]) -> dict[str, dict]:
    refuse_odd_numbers(path, body, "its elements")  # float() and int() below would read "1_0" as 10
    values = numbers(body, np.float64)
    if values is None:
        word = next((w for w in body.split() if numbers(w, np.float64) is None), None)  # a broken file: the word
        shown = (
            "its elements are not all numbers"
            if word is None
            else f"{word.decode('ascii', 'replace')!r} is not a number"
        )
        raise SceneFileError(f"{path}: {shown}")
    at = 0
    out: dict[str, dict] = {}  # element → property → values
    for e in elements:
        if all(p.count_type is None for p in e.properties):  # a table of numbers
            n = e.count * len(e.properties)
            if at + n > len(values):
                raise SceneFileError(f"{path}: the file ends inside its {e.name} elements (truncated?)")
            table = values[at : at + n].reshape(e.count, len(e.properties))
            out[e.name] = {p.name: table[:, i] for i, p in enumerate(e.properties)}
            at += n
        else:
            out[e.name], at = ascii_element(path, values, at, e)
        for p in e.properties:
            _check_integers(path, e.name, p, out[e.name][p.name])
    if at != len(values):
        raise SceneFileError(f"{path}: {len(values) - at} values after the elements the header declares")
    return out


def _check_integers(path: Path, element: str, p: _Property, column: np.ndarray | Lists) -> None:
    """An ASCII column (or list) of an integer type holds integers within it: `uchar x` of -1000
    and `int x` of 0.5 were read as they were written, as floats (a helper's audit)."""
    if p.type[0] not in "iu":
        return
    values = column.items if isinstance(column, Lists) else column
    info = np.iinfo(np.dtype(p.type))
    bad = np.flatnonzero((values != np.floor(values)) | (values < info.min) | (values > info.max))
    if len(bad):
        k = int(bad[0])
        at = int(np.searchsorted(np.cumsum(column.sizes), k, side="right")) if isinstance(column, Lists) else k
        raise SceneFileError(
            f"{path}: {element} {at}'s {p.name} is {values[k]:g}, not a {np.dtype(p.type).name} "
            "(the type its header declares)"
        )


def _read_binary(path: Path, data: bytes, at: int, elements: list[_Element], order: str) -> dict:
    out = {}
    for e in elements:
        if all(p.count_type is None for p in e.properties):
            dtype = np.dtype([(f"p{i}", order + p.type) for i, p in enumerate(e.properties)])
            size = dtype.itemsize * e.count
            if at + size > len(data):
                raise SceneFileError(f"{path}: the file ends inside its {e.name} elements (truncated?)")
            table = np.frombuffer(data, dtype, e.count, at)
            out[e.name] = {p.name: table[f"p{i}"] for i, p in enumerate(e.properties)}
            at += size
        else:
            out[e.name], at = binary_element(path, data, at, e, order)
    if at != len(data):
        raise SceneFileError(f"{path}: {len(data) - at} bytes after the elements the header declares")
    return out


def _triangles(path: Path, lists: Lists, positions: np.ndarray) -> np.ndarray:
    """The faces' triangles; points and edges (fewer than 3 corners) are dropped unread."""
    corners = lists.items.astype(np.int64)
    wrong = ((corners < 0) | (corners >= len(positions))) & np.repeat(lists.sizes >= 3, lists.sizes)
    if wrong.any():
        face = int(np.searchsorted(np.cumsum(lists.sizes), int(np.argmax(wrong)), side="right"))
        raise SceneFileError(f"{path}: face {face} refers to a vertex that does not exist (have {len(positions)})")
    return triangulate_runs(corners, lists.sizes, positions)
