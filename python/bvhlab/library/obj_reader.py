"""Wavefront OBJ's geometry (Wavefront Technologies, "Object Files (.obj)", Appendix B1 of the
Advanced Visualizer manual): `v` positions and `f` polygons, the rest (normals, texture
coordinates, groups, materials, lines, points) skipped. As the format says and Blender reads it:
statements split on any whitespace, `#` starts a comment anywhere on a line, a backslash at a
line's end continues it, a negative index counts back from the last vertex defined *so far* (not
from the file's end), and 0 is no index (refused). Polygons are triangulated by polygons.py."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .._npz import SceneFileError
from .polygons import triangulate_runs
from .text_bytes import numbers, refuse_nul, refuse_odd_numbers, utf8_bytes


def read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """float64 (V, 3) positions and int64 (T, 3) triangles of the OBJ file at `path`. The text is
    read in runs of whole lines (CHUNK characters): each run's statements are sorted out and their
    numbers parsed in numpy (a million-triangle file in a few seconds), so that the lines as Python
    strings never exist all at once: a 157 MB file of a million vertices took 1.6 GB read whole
    (ten times the file), 0.47 GB in runs. The first wrong vertex index of the file is named, as
    read whole; of errors of other kinds (a vertex without three numbers, a face of words that are
    not indices) that of the earliest run is, in a file larger than CHUNK."""
    text = _text(path)
    vertices: list[np.ndarray] = []
    faces = _Faces()
    first, count = 1, 0  # the file's line number of the run's first line; vertices before it
    for run in _runs(text, CHUNK):
        vertex_lines, face_lines, face_numbers, defined = _statements(run, first, count)
        vertices.append(_vertices(path, vertex_lines, count))
        faces.add(path, face_lines, face_numbers, defined)
        first, count = first + run.count("\n"), count + len(vertex_lines)
    positions = np.concatenate(vertices) if vertices else np.zeros((0, 3))
    resolved, sizes = faces.resolved(path, text, len(positions))
    return positions, triangulate_runs(resolved, sizes, positions)


#: Characters of text read at once (lines are not split: a run ends at the first line end after).
CHUNK = 1 << 23


def _text(path: Path) -> str:
    """The file as text whose lines end at \\n: CR LF and CR made LF, odd spaces spaces, a line
    continued by a backslash joined to the next."""
    data = utf8_bytes(path, path.read_bytes())
    refuse_nul(path, data, "OBJ")
    text = data.decode("utf-8", errors="replace").lstrip("\ufeff")
    del data
    text = text.replace("\r\n", "\n").replace("\r", "\n")  # lines end at \n, \r\n or \r only
    if _ODD_SPACE.search(text):  # \v, \f, no-break or line-separator spaces: spaces, not line ends
        text = _ODD_SPACE.sub(" ", text)
    return _CONTINUED.sub(" ", text)


def _runs(text: str, size: int):
    """`text` in runs of whole lines, each of at least `size` characters but the last."""
    start = 0
    while start < len(text):
        end = text.find("\n", start + size)
        end = len(text) if end < 0 else end + 1
        yield text[start:end]
        start = end


def _statements(run: str, first: int, vertices_before: int) -> tuple[list[str], list[str], list[int], list[int]]:
    """The `v` lines, the `f` lines, each face's line number and the vertices defined before each
    face (negative indices count back from there) of a run of lines numbered from `first`."""
    vertex_lines: list[str] = []
    face_lines: list[str] = []
    face_numbers: list[int] = []
    defined: list[int] = []
    comments = "#" in run
    for number, line in enumerate(run.split("\n"), first):
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
            defined.append(vertices_before + len(vertex_lines))
    return vertex_lines, face_lines, face_numbers, defined


class _Faces:
    """The faces of the runs read so far: each corner's vertex, resolved (a negative index counted
    back from the vertices defined before its face), the corners of each face and its line. A
    wrong index (0, before the first vertex, past the file's last: a face may name a vertex defined
    after it) is refused once every vertex is read, the first in the file named."""

    def __init__(self) -> None:
        self.corners: list[np.ndarray] = []
        self.sizes: list[np.ndarray] = []
        self.numbers: list[np.ndarray] = []
        self.wrong: tuple[int, str] | None = None  # the first corner refused so far, and why

    def add(self, path: Path, face_lines: list[str], face_numbers: list[int], defined: list[int]) -> None:
        sizes = _word_counts(face_lines) - 1  # corners of each face
        # each corner's vertex index: `v`, `v/vt`, `v//vn` or `v/vt/vn`
        index = numbers(re.sub(r"/\S*", "", " ".join(line[1:] for line in face_lines)), np.int64)
        if index is None or index.size != sizes.sum():
            for line, number in zip(face_lines, face_numbers):  # the line to name
                if not all(_is_index(w) for w in line.split()[1:]):
                    raise SceneFileError(f"{path}, line {number}: {line!r} is not vertex indices")
            raise SceneFileError(f"{path}: faces that are not vertex indices")  # not reached: a line fails above
        face_of = np.repeat(np.arange(len(face_lines)), sizes)
        before = np.asarray(defined, np.int64)[face_of]
        resolved = np.where(index > 0, index - 1, before + index)
        wrong = (index == 0) | (resolved < 0)
        if wrong.any() and self.wrong is None:
            k = int(np.argmax(wrong))
            face = int(face_of[k])
            at, i = face_numbers[face], int(index[k])
            if i == 0:
                message = f"{path}, line {at}: vertex index 0 (OBJ counts vertices from 1)"
            else:
                written = _written(face_lines[face], k - int(np.cumsum(sizes)[face] - sizes[face]))
                message = f"{path}, line {at}: vertex {written} does not exist ({defined[face]} defined before it)"
            self.wrong = (sum(len(c) for c in self.corners) + k, message)
        self.corners.append(resolved)
        self.sizes.append(sizes)
        self.numbers.append(np.asarray(face_numbers, np.int64))

    def resolved(self, path: Path, text: str, vertex_count: int) -> tuple[np.ndarray, np.ndarray]:
        """Every corner's vertex and every face's corner count, with none past the last vertex."""
        resolved = np.concatenate(self.corners) if self.corners else np.zeros(0, np.int64)
        sizes = np.concatenate(self.sizes) if self.sizes else np.zeros(0, np.int64)
        past = resolved >= vertex_count
        first_past = int(np.argmax(past)) if past.any() else len(resolved)
        if self.wrong is not None and self.wrong[0] <= first_past:
            raise SceneFileError(self.wrong[1])
        if first_past < len(resolved):
            k = first_past
            ends = np.cumsum(sizes)
            face = int(np.searchsorted(ends, k, side="right"))
            at = int(np.concatenate(self.numbers)[face])
            written = _written(_line(text, at), k - int(ends[face] - sizes[face]))
            raise SceneFileError(f"{path}, line {at}: vertex {written} does not exist (the file has {vertex_count})")
        return resolved, sizes


def _line(text: str, number: int) -> str:
    """Line `number` (from 1) of `text`, its comment cut: found run by run (splitting the whole
    text would make every line a string)."""
    first = 1
    for run in _runs(text, CHUNK):
        ends = run.count("\n")
        if number < first + ends + (not run.endswith("\n")):  # the lines this run holds
            return run.split("\n")[number - first].split("#", 1)[0].strip()
        first += ends
    raise IndexError(number)


def _written(line: str, corner: int) -> str:
    """A face line's corner's vertex index as written (numpy's parse saturates one past int64 at
    2^63 - 1)."""
    return line.split()[1 + corner].split("/")[0]


#: Whitespace other than a space, a tab or a line end (Python's \s: \v, \f, U+0085, U+00A0,
#: U+2028, ...): str.splitlines ended lines there (a commented-out face after U+2028 was read).
_ODD_SPACE = re.compile(r"[^\S\n \t]")
#: A backslash at a line's end (spaces may follow it) joins the next line, as OBJ writers use it.
_CONTINUED = re.compile(r"\\[ \t]*(?:\n|$)")


def _vertices(path: Path, lines: list[str], before: int) -> np.ndarray:
    """float64 (V, 3): x, y, z of each `v` line (w or a colour after them ignored); `before`
    vertices precede the first (for the message)."""
    counts = _word_counts(lines) - 1
    values = numbers(" ".join(line[1:] for line in lines), np.float64) if (counts == 3).all() else None
    if values is not None and values.size == 3 * len(lines):  # the usual file: "v x y z" on every line
        return values.reshape(-1, 3)
    rows = [line.split()[1:4] for line in lines]
    short = next((i for i, r in enumerate(rows) if len(r) < 3), None)
    if short is not None:
        raise SceneFileError(f"{path}: vertex {before + short + 1} needs x, y and z, got {lines[short]!r}")
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


def _is_index(word: str) -> bool:
    try:
        return -(2**63) <= int(word.split("/", 1)[0]) < 2**63
    except ValueError:
        return False
