"""A PLY element with list properties (Turk 1994: a face's `vertex_indices`), ASCII or binary, as
arrays: a scalar property as a column, a list property as `Lists` (the items of every element
laid end to end and each element's count). Where every element's lists have the first element's
lengths (a mesh of triangles, or of quads) the records are one numpy table; otherwise each
record's place is found in a loop over the records, and the values are gathered by a mask over
the file. The lists were Python tuples of Python numbers: a binary PLY of 2 million triangles
(38 MB) took 560 MB, an ASCII one (73 MB) 1.1 GB."""

from __future__ import annotations

import struct
from array import array
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._npz import SceneFileError


@dataclass
class Lists:
    items: np.ndarray  # every element's items, end to end
    sizes: np.ndarray  # int64: each element's count of items


def binary_element(path: Path, data: bytes, at: int, e, order: str) -> tuple[dict, int]:
    """Element `e` (ply_reader._Element) of binary `data` from byte `at`: its columns, and the
    byte after its last record."""
    first = _first_counts_binary(data, at, e, order)
    if first is not None:
        fields: list[tuple] = []
        for i, p in enumerate(e.properties):
            if p.count_type is None:
                fields.append((f"v{i}", order + p.type))
            else:
                fields.append((f"n{i}", order + p.count_type))
                fields.append((f"v{i}", order + p.type, (first[i],)))
        table_type = np.dtype(fields)
        if at + table_type.itemsize * e.count <= len(data):
            table = np.frombuffer(data, table_type, e.count, at)
            if all(p.count_type is None or (table[f"n{i}"] == first[i]).all() for i, p in enumerate(e.properties)):
                return _columns(e, table, first), at + table_type.itemsize * e.count
    places, counts, at = _binary_places(path, data, at, e, order)
    raw = np.frombuffer(data, np.uint8)
    out: dict[str, np.ndarray | Lists] = {}
    for i, p in enumerate(e.properties):
        size = np.dtype(p.type).itemsize
        if p.count_type is None:
            out[p.name] = _gather(raw, places[i], np.full(e.count, size)).view(order + p.type)
            continue
        sizes = np.frombuffer(counts[i], np.int64)
        starts = np.frombuffer(places[i], np.int64) + np.dtype(p.count_type).itemsize
        out[p.name] = Lists(_gather(raw, starts, sizes * size).view(order + p.type), sizes)
    return out, at


def ascii_element(path: Path, values: np.ndarray, at: int, e) -> tuple[dict, int]:
    """Element `e` of an ASCII body whose numbers are `values` (float64), from number `at`: its
    columns (float64; list items checked to be whole for integer types by the caller), and the
    number after its last record."""
    first = _first_counts_ascii(path, values, at, e)
    if first is not None:
        width = sum(1 if p.count_type is None else 1 + first[i] for i, p in enumerate(e.properties))
        if at + width * e.count <= len(values):
            table = values[at : at + width * e.count].reshape(e.count, width)
            column, checks = 0, []
            for i, p in enumerate(e.properties):
                if p.count_type is not None:
                    checks.append(table[:, column] == first[i])
                    column += first[i]
                column += 1
            if all(c.all() for c in checks):
                return _ascii_columns(e, table, first), at + width * e.count
    places, counts, at = _ascii_places(path, values, at, e)
    out: dict[str, np.ndarray | Lists] = {}
    for i, p in enumerate(e.properties):
        if p.count_type is None:
            out[p.name] = values[np.frombuffer(places[i], np.int64)]
            continue
        sizes = np.frombuffer(counts[i], np.int64)
        out[p.name] = Lists(_gather(values, np.frombuffer(places[i], np.int64) + 1, sizes), sizes)
    return out, at


def _columns(e, table: np.ndarray, first: dict[int, int]) -> dict:
    out: dict[str, np.ndarray | Lists] = {}
    for i, p in enumerate(e.properties):
        if p.count_type is None:
            out[p.name] = table[f"v{i}"]
        else:
            out[p.name] = Lists(table[f"v{i}"].reshape(-1), np.full(len(table), first[i], np.int64))
    return out


def _ascii_columns(e, table: np.ndarray, first: dict[int, int]) -> dict:
    out: dict[str, np.ndarray | Lists] = {}
    column = 0
    for i, p in enumerate(e.properties):
        if p.count_type is None:
            out[p.name] = table[:, column]
            column += 1
        else:
            k = first[i]
            out[p.name] = Lists(table[:, column + 1 : column + 1 + k].reshape(-1), np.full(len(table), k, np.int64))
            column += 1 + k
    return out


def _first_counts_binary(data: bytes, at: int, e, order: str) -> dict[int, int] | None:
    """The list lengths of the first record, by property; None where there is no record, or a
    list of no items (the records are then read one by one)."""
    first = {}
    if e.count == 0:
        return None
    try:
        for i, p in enumerate(e.properties):
            if p.count_type is None:
                at += np.dtype(p.type).itemsize
                continue
            (k,) = struct.unpack_from(order + np.dtype(p.count_type).char, data, at)
            if k < 0:
                return None
            if k == 0:  # a table field of no items: read record by record
                return None
            first[i] = int(k)
            at += np.dtype(p.count_type).itemsize + k * np.dtype(p.type).itemsize
    except struct.error:
        return None
    return first


def _first_counts_ascii(path: Path, values: np.ndarray, at: int, e) -> dict[int, int] | None:
    first = {}
    if e.count == 0:
        return None
    for i, p in enumerate(e.properties):
        if p.count_type is not None:
            if at >= len(values):
                return None
            first[i] = _count(path, e, values[at])
            if first[i] == 0:
                return None
            at += first[i]
        at += 1
    return first


def _count(path: Path, e, value: float) -> int:
    """A list's length as written in ASCII: a whole number >= 0."""
    if not (value >= 0 and float(value).is_integer()):
        raise SceneFileError(f"{path}: a {e.name} element is not PLY (a list of {value:g} items)")
    return int(value)


def _binary_places(path: Path, data: bytes, at: int, e, order: str) -> tuple[list[array], list[array], int]:
    """Record by record: where each property starts, and each list's length."""
    places = [array("q") for _ in e.properties]
    counts = [array("q") for _ in e.properties]
    steps = [
        (
            places[i].append,
            counts[i].append,
            np.dtype(p.type).itemsize,
            p.count_type and struct.Struct(order + np.dtype(p.count_type).char),
        )
        for i, p in enumerate(e.properties)
    ]
    try:
        for _ in range(e.count):
            for place, count, size, length in steps:
                place(at)
                if not length:
                    at += size
                    continue
                (k,) = length.unpack_from(data, at)
                if k < 0:
                    raise SceneFileError(f"{path}: a {e.name} element has a list of {k} items")
                count(k)
                at += length.size + k * size
    except struct.error:  # past the end
        at = len(data) + 1
    if at > len(data):
        raise SceneFileError(f"{path}: the file ends inside its {e.name} elements (truncated?)")
    return places, counts, at


def _ascii_places(path: Path, values: np.ndarray, at: int, e) -> tuple[list[array], list[array], int]:
    places = [array("q") for _ in e.properties]
    counts = [array("q") for _ in e.properties]
    steps = [(places[i].append, counts[i].append, p.count_type is not None) for i, p in enumerate(e.properties)]
    read = memoryview(values.data)  # a float a read, without numpy's scalar
    try:
        for _ in range(e.count):
            for place, count, is_list in steps:
                place(at)
                if is_list:
                    k = _count(path, e, read[at])
                    count(k)
                    at += k
                at += 1
    except IndexError:
        at = len(values) + 1
    if at > len(values):
        raise SceneFileError(f"{path}: the file ends inside its {e.name} elements (truncated?)")
    return places, counts, at


def _gather(source: np.ndarray, starts, lengths: np.ndarray) -> np.ndarray:
    """The runs source[starts[k] : starts[k] + lengths[k]] end to end, by a mask over `source` (runs
    in ascending order, apart): no index for each value, which would take 8 bytes a byte. Starts
    are distinct, and so are ends (a run may end where the next starts: +1 and -1 there)."""
    starts = np.asarray(starts, np.int64)[lengths > 0]
    edges = np.zeros(len(source) + 1, np.int8)
    edges[starts] += 1
    edges[starts + lengths[lengths > 0]] -= 1
    return source[np.cumsum(edges[:-1], dtype=np.int8).view(bool)]
