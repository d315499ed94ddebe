"""The OBJ reader reads its text in runs of lines (obj_reader.CHUNK characters), so that a large
file's lines never exist as Python strings all at once. Read in runs of a few characters, every
file reads as in one run: the same positions and triangles, the same error named on the same
line (negative indices counting back across runs, faces naming vertices of a later run, continued
lines, comments, CR line ends); and a file of many runs is read in memory a few times its size
(read whole: ten times)."""

import tracemalloc

import numpy as np
import pytest

from bvhlab._npz import SceneFileError
from bvhlab.library import obj_reader
from bvhlab.library.obj_reader import read_obj

FILES = {
    "relative": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nv 6 5 5\nv 6 6 5\nf -3 -2 -1\nf 1 -2 -1\n",
    "forward": "f 1/1/1 2//1 3/2 4\n# a comment\nv 0 0 0 # origin\nv 1 0\\\n 0\nv 0 1 0 1.0\nvn 0 0 1\nv 1 1 0\n",
    "crlf": "v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nv 1 1 0\rf 1 2 4 3\r\nf -4 -3 -2\r\n",
    "zero": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 5\nv 1 1 1\nf 0 1 2\n",
    "negative": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\nf -4 -2 -1\nv 1 1 1\n",
    "past": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 0\nv 1 1 1\nf 1 2 \\\n 5\n",
    "past first": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\nv 1 1 1\nf -9 1 2\n",
    "words": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 1 1 1\nf 1 2 x\n",
    "last line": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4",  # no line end after the wrong index
}


def read(path):
    try:
        vertices, triangles = read_obj(path)
        return vertices.tolist(), triangles.tolist()
    except SceneFileError as e:
        return str(e)


@pytest.mark.parametrize("name", FILES)
def test_runs_of_any_length_read_as_one(tmp_path, monkeypatch, name):
    path = tmp_path / "mesh.obj"
    path.write_text(FILES[name], newline="")
    whole = read(path)
    for size in (1, 2, 5, 11, 17, 40):
        monkeypatch.setattr(obj_reader, "CHUNK", size)
        assert read(path) == whole, size
    if name in ("zero", "negative", "past", "past first", "words", "last line"):
        expected = {
            "zero": "line 5: vertex 5 does not exist (the file has 4)",
            "negative": "line 5: vertex 9 does not exist (the file has 4)",
            "past": "line 5: vertex index 0",
            "past first": "line 5: vertex 7 does not exist (the file has 4)",
            "words": "line 6: 'f 1 2 x' is not vertex indices",
            "last line": "line 5: vertex 4 does not exist (the file has 3)",
        }[name]
        assert isinstance(whole, str) and expected in whole
    else:
        assert not isinstance(whole, str), whole


def test_the_first_wrong_index_of_a_later_run_is_named(tmp_path, monkeypatch):
    lines = [f"v {i} 0 {i % 3}" for i in range(60)] + [f"f {i + 1} {i + 2} {i + 3}" for i in range(50)]
    lines[85] = "f 1 2 -61"  # 60 vertices are defined before it
    path = tmp_path / "late.obj"
    path.write_text("\n".join(lines) + "\n")
    monkeypatch.setattr(obj_reader, "CHUNK", 64)
    with pytest.raises(SceneFileError, match="line 86: vertex -61 does not exist .60 defined before it."):
        read_obj(path)


def test_a_file_of_many_runs_is_read_in_a_few_times_its_size(tmp_path, monkeypatch):
    k = 300  # a grid of 90,000 vertices and 178,802 triangles, corners written v/vt/vn
    x, y = np.meshgrid(np.arange(k), np.arange(k))
    i = (y[:-1, :-1] * k + x[:-1, :-1]).ravel() + 1
    faces = np.concatenate([np.stack([i, i + 1, i + k], 1), np.stack([i + 1, i + k + 1, i + k], 1)])
    text = "".join(f"v {a * 0.01:.6f} {b * 0.01:.6f} {np.sin(a * 0.1):.6f}\n" for a, b in zip(x.ravel(), y.ravel()))
    text += "".join(f"f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}\n" for a, b, c in faces)
    path = tmp_path / "grid.obj"
    path.write_text(text)
    size = path.stat().st_size
    monkeypatch.setattr(obj_reader, "CHUNK", 1 << 20)  # ~9 runs
    tracemalloc.start()
    try:
        vertices, triangles = read_obj(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    np.testing.assert_array_equal(triangles, faces - 1)
    assert vertices.shape == (k * k, 3) and vertices[k + 2].tolist() == [0.02, 0.01, round(np.sin(0.2), 6)]
    assert peak < 4 * size, (peak, size)  # 2.75 times; read whole, as one run: 9.7 times
