"""PLY's geometry (Turk, "The PLY Polygon File Format", 1994): the `vertex` element's x, y, z and
the `face` element's vertex_indices (or vertex_index) lists, in ASCII or binary of either byte
order; every other element and property is read past. Faces of any size in one file (Blender's
binary export of a mesh of triangles and quads), triangulated by polygons.py. The header's counts
are the file's: a file that ends early or goes on after its last element is refused."""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._npz import SceneFileError
from .polygons import triangulate_all
from .text_bytes import refuse_odd_numbers, utf8_bytes

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
    if kind.type[0] == "f":  # indices written as floats (rare writers): whole numbers only
        if not all(float(c).is_integer() for corners in lists for c in corners):
            raise SceneFileError(f"{path}: the face element's {name} holds numbers that are not indices")
        lists = [[int(c) for c in corners] for corners in lists]
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
    words = body.split()
    at = 0
    out: dict[str, dict] = {}  # element → property → values
    for e in elements:
        if all(p.count_type is None for p in e.properties):  # a table of numbers
            n = e.count * len(e.properties)
            if at + n > len(words):
                raise SceneFileError(f"{path}: the file ends inside its {e.name} elements (truncated?)")
            table = np.array(words[at : at + n], dtype=np.float64).reshape(e.count, len(e.properties))
            for i, p in enumerate(e.properties):
                _check_integers(path, e.name, p, table[:, i])
            out[e.name] = {p.name: table[:, i] for i, p in enumerate(e.properties)}
            at += n
            continue
        columns: dict[str, list] = {p.name: [] for p in e.properties}
        try:
            for _ in range(e.count):
                for p in e.properties:
                    if p.count_type is None:
                        columns[p.name].append(float(words[at]))
                        at += 1
                    else:
                        k = int(words[at])
                        if k < 0:
                            raise ValueError(f"a list of {k} items")
                        number = float if p.type[0] == "f" else int  # texture coordinates are lists too
                        columns[p.name].append([number(w) for w in words[at + 1 : at + 1 + k]])
                        if len(columns[p.name][-1]) < k:
                            raise IndexError
                        at += 1 + k
        except IndexError:
            raise SceneFileError(f"{path}: the file ends inside its {e.name} elements (truncated?)") from None
        except ValueError as err:
            raise SceneFileError(f"{path}: a {e.name} element is not PLY ({err})") from None
        out[e.name] = columns
    if at != len(words):
        raise SceneFileError(f"{path}: {len(words) - at} values after the elements the header declares")
    return out


def _check_integers(path: Path, element: str, p: _Property, values: np.ndarray) -> None:
    """An ASCII column of an integer type holds integers within it: `uchar x` of -1000 and `int x`
    of 0.5 were read as they were written, as floats (a helper's audit)."""
    if p.type[0] not in "iu":
        return
    info = np.iinfo(np.dtype(p.type))
    bad = np.flatnonzero((values != np.floor(values)) | (values < info.min) | (values > info.max))
    if len(bad):
        raise SceneFileError(
            f"{path}: {element} {bad[0]}'s {p.name} is {values[bad[0]]:g}, not a {np.dtype(p.type).name} "
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
            out[e.name], at = _binary_lists(path, data, at, e, order)
    if at != len(data):
        raise SceneFileError(f"{path}: {len(data) - at} bytes after the elements the header declares")
    return out


def _binary_lists(path: Path, data: bytes, at: int, e: _Element, order: str) -> tuple[dict, int]:
    """An element with lists, record by record (each list's length is in the data)."""
    columns: dict[str, list] = {p.name: [] for p in e.properties}
    steps = [
        (
            columns[p.name],
            struct.Struct(order + np.dtype(p.type).char),  # numpy's type codes are struct's
            p.count_type and struct.Struct(order + np.dtype(p.count_type).char),
        )
        for p in e.properties
    ]
    lists: dict[tuple[str, int], struct.Struct] = {}
    try:
        for _ in range(e.count):
            for column, item, count in steps:
                if not count:
                    column.append(item.unpack_from(data, at)[0])
                    at += item.size
                    continue
                (k,) = count.unpack_from(data, at)
                at += count.size
                if k < 0:
                    raise SceneFileError(f"{path}: a {e.name} element has a list of {k} items")
                items = lists.get((item.format, k)) or lists.setdefault(
                    (item.format, k), struct.Struct(f"{order}{k}{item.format[-1]}")
                )
                column.append(items.unpack_from(data, at))
                at += items.size
    except struct.error:  # past the end
        raise SceneFileError(f"{path}: the file ends inside its {e.name} elements (truncated?)") from None
    return columns, at


def _triangles(path: Path, lists, positions: np.ndarray) -> np.ndarray:
    for i, corners in enumerate(lists):  # points and edges (fewer than 3 corners) are dropped unread
        if len(corners) >= 3 and (min(corners) < 0 or max(corners) >= len(positions)):
            raise SceneFileError(f"{path}: face {i} refers to a vertex that does not exist (have {len(positions)})")
    return triangulate_all([c for c in lists if len(c) >= 3], positions)  # points and edges: no surface
