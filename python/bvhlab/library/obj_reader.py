"""Wavefront OBJ's geometry (Wavefront Technologies, "Object Files (.obj)", Appendix B1 of the
Advanced Visualizer manual): `v` positions and `f` polygons, the rest (normals, texture
coordinates, groups, materials, lines, points) skipped. As the format says and Blender reads it:
statements split on any whitespace, `#` starts a comment anywhere on a line, a backslash at a
line's end continues it, a negative index counts back from the last vertex defined *so far* (not
from the file's end), and 0 is no index (refused). Polygons are triangulated by polygons.py."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np

from .._npz import SceneFileError
from .polygons import triangulate_runs
from .text_bytes import refuse_nul, refuse_odd_numbers, utf8_bytes


def read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """float64 (V, 3) positions and int64 (T, 3) triangles of the OBJ file at `path`. One pass
    over the lines sorts out the statements; numbers are parsed in numpy (a million-triangle file
    in a few seconds)."""
    data = utf8_bytes(path, path.read_bytes())
    refuse_nul(path, data, "OBJ")
    text = data.decode("utf-8", errors="replace").lstrip("\ufeff")
    text = text.replace("\r\n", "\n").replace("\r", "\n")  # lines end at \n, \r\n or \r only
    if _ODD_SPACE.search(text):  # \v, \f, no-break or line-separator spaces: spaces, not line ends
        text = _ODD_SPACE.sub(" ", text)
    text = _CONTINUED.sub(" ", text)
    vertex_lines: list[str] = []
    face_lines: list[str] = []
    face_numbers: list[int] = []  # the file's line of each face
    defined: list[int] = []  # vertices defined before each face (negative indices count from there)
    comments = "#" in text
    for number, line in enumerate(text.split("\n"), 1):
        if comments:
            line = line.split("#", 1)[0]
        line = line.strip()
        if len(line) < 2 or line[1] not in " \t":
            continue
        if line[0] == "v":
            vertex_lines.append(line)
        elif line[0] == "f":
            face_lines.append(line)
            face_numbers.append(number)
            defined.append(len(vertex_lines))
    vertices = _vertices(path, vertex_lines)
    sizes = _word_counts(face_lines) - 1  # corners of each face
    # each corner's vertex index: `v`, `v/vt`, `v//vn` or `v/vt/vn`
    index = _numbers(re.sub(r"/\S*", "", " ".join(line[1:] for line in face_lines)), np.int64)
    if index is None or index.size != sizes.sum():
        for line, number in zip(face_lines, face_numbers):  # the line to name
            if not all(_is_index(w) for w in line.split()[1:]):
                raise SceneFileError(f"{path}, line {number}: {line!r} is not vertex indices")
        raise SceneFileError(f"{path}: faces that are not vertex indices")  # not reached: a line fails above
    face_of = np.repeat(np.arange(len(face_lines)), sizes)
    resolved = np.where(index > 0, index - 1, np.asarray(defined, np.int64)[face_of] + index)
    wrong = (index == 0) | (resolved < 0) | (resolved >= len(vertices))
    if wrong.any():
        k = int(np.argmax(wrong))
        face = int(face_of[k])
        at, i = face_numbers[face], int(index[k])
        # the index as written (numpy's parse saturates one past int64 at 2^63 - 1)
        written = face_lines[face].split()[1 + k - int(np.cumsum(sizes)[face] - sizes[face])].split("/")[0]
        if i == 0:
            raise SceneFileError(f"{path}, line {at}: vertex index 0 (OBJ counts vertices from 1)")
        if i < 0:
            raise SceneFileError(
                f"{path}, line {at}: vertex {written} does not exist ({defined[face]} defined before it)"
            )
        raise SceneFileError(f"{path}, line {at}: vertex {written} does not exist (the file has {len(vertices)})")
    if len(sizes) and (sizes == 3).all():  # triangles only
        return vertices, resolved.reshape(-1, 3)
    return vertices, triangulate_runs(resolved, sizes, vertices)


#: Whitespace other than a space, a tab or a line end (Python's \s: \v, \f, U+0085, U+00A0,
#: U+2028, ...): str.splitlines ended lines there (a commented-out face after U+2028 was read).
_ODD_SPACE = re.compile(r"[^\S\n \t]")
#: A backslash at a line's end (spaces may follow it) joins the next line, as OBJ writers use it.
_CONTINUED = re.compile(r"\\[ \t]*(?:\n|$)")


def _vertices(path: Path, lines: list[str]) -> np.ndarray:
    """float64 (V, 3): x, y, z of each `v` line (w or a colour after them ignored)."""
    counts = _word_counts(lines) - 1
    values = _numbers(" ".join(line[1:] for line in lines), np.float64) if (counts == 3).all() else None
    if values is not None and values.size == 3 * len(lines):  # the usual file: "v x y z" on every line
        return values.reshape(-1, 3)
    rows = [line.split()[1:4] for line in lines]
    short = next((i for i, r in enumerate(rows) if len(r) < 3), None)
    if short is not None:
        raise SceneFileError(f"{path}: vertex {short + 1} needs x, y and z, got {lines[short]!r}")
    # float() reads "1_0" as 10 and "１" as 1, where the fast parse refuses both
    refuse_odd_numbers(path, " ".join(" ".join(r) for r in rows).encode(), "a vertex coordinate")
    try:
        return np.array(rows, dtype=np.float64).reshape(-1, 3)
    except ValueError as e:
        raise SceneFileError(f"{path}: a vertex coordinate is not a number ({e})") from None


def _word_counts(lines: list[str]) -> np.ndarray:
    """int64 (len(lines),): whitespace-separated words on each line, counted in numpy."""
    if not lines:
        return np.zeros(0, np.int64)
    text = np.frombuffer("\n".join(lines).encode("utf-8"), np.uint8)
    space = (text == 32) | (text == 9) | (text == 10) | (text == 13) | (text == 11) | (text == 12)
    starts = np.flatnonzero(~space & np.concatenate([[True], space[:-1]]))
    line_of = np.searchsorted(np.flatnonzero(text == 10), starts)  # newlines before each word
    return np.bincount(line_of, minlength=len(lines)).astype(np.int64)


def _numbers(text: str, dtype) -> np.ndarray | None:
    """The whitespace-separated numbers of `text` parsed in C; None if one is not a number."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)  # numpy < 2.x: a partial read warns
        try:
            return np.fromstring(text, dtype=dtype, sep=" ")
        except (ValueError, DeprecationWarning):
            return None


def _is_index(word: str) -> bool:
    try:
        return -(2**63) <= int(word.split("/", 1)[0]) < 2**63
    except ValueError:
        return False
