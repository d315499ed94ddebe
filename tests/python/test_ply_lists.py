"""PLY elements with lists (ply_lists.py), read as one numpy table where every element's lists
have the same length and record by record where they do not, in ASCII and binary of both byte
orders, with properties before and after the list and a second list: the triangles written here
come back in their order; an integer list holding what its type cannot is refused; and a file of
2 × 300² triangles is read in memory a few times its size (the lists as Python tuples: 11 to 14 times)."""

import struct
import tracemalloc

import numpy as np
import pytest

from bvhlab._npz import SceneFileError
from bvhlab.library.ply_reader import read_ply

VERTICES = [(float(i), float(i * i % 7), float(i % 3)) for i in range(9)]


def ply(fmt: str, faces: list[list[int]], flags: bool, texcoords: bool, tag: bool) -> bytes:
    """A PLY of VERTICES and `faces`, each face record: [flags] vertex_indices [texcoord] [tag]."""
    head = f"ply\nformat {fmt} 1.0\nelement vertex {len(VERTICES)}\n"
    head += "property float x\nproperty float y\nproperty float z\n" + f"element face {len(faces)}\n"
    head += "property uchar flags\n" * flags + "property list uchar int vertex_indices\n"
    head += "property list uchar float texcoord\n" * texcoords + "property short tag\n" * tag + "end_header\n"
    records = []
    for n, f in enumerate(faces):
        uv = [0.5] * (2 * (n % 3))  # lists of 0, 2 and 4 items
        records.append(([n % 5] if flags else [], f, uv if texcoords else None, [-n] if tag else []))
    if fmt == "ascii":
        body = "".join(" ".join(map(str, v)) + "\n" for v in VERTICES)
        for before, f, uv, after in records:
            words = before + [len(f), *f] + ([len(uv), *uv] if uv is not None else []) + after
            body += " ".join(map(str, words)) + "\n"
        return (head + body).encode()
    o = "<" if fmt == "binary_little_endian" else ">"
    body = b"".join(struct.pack(o + "fff", *v) for v in VERTICES)
    for before, f, uv, after in records:
        body += struct.pack(o + "B" * len(before), *before) + struct.pack(f"{o}B{len(f)}i", len(f), *f)
        body += struct.pack(f"{o}B{len(uv)}f", len(uv), *uv) if uv is not None else b""
        body += struct.pack(o + "h" * len(after), *after)
    return head.encode() + body


TRIANGLES = [[0, 1, 2], [3, 4, 5], [6, 7, 8], [2, 4, 6], [8, 0, 5]]
# triangles and, within the first two, an edge and a point (no triangles: dropped)
MIXED = [[0, 1, 2], [4, 5], [3, 4, 5], [7], [6, 7, 8], [2, 4, 6], [8, 0, 5]]


@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian", "binary_big_endian"])
@pytest.mark.parametrize("faces", [TRIANGLES, MIXED], ids=["same lengths", "mixed lengths"])
@pytest.mark.parametrize("flags, texcoords, tag", [(0, 0, 0), (1, 0, 1), (0, 1, 0), (1, 1, 1)])
def test_faces_come_back_in_their_order(tmp_path, fmt, faces, flags, texcoords, tag):
    path = tmp_path / "mesh.ply"
    path.write_bytes(ply(fmt, faces, flags, texcoords, tag))
    positions, triangles = read_ply(path)
    np.testing.assert_array_equal(positions, np.array(VERTICES, np.float32))
    np.testing.assert_array_equal(triangles, TRIANGLES)


@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian"])
def test_a_list_running_past_the_file_is_refused(tmp_path, fmt):
    data = ply(fmt, MIXED, 1, 1, 1)
    path = tmp_path / "cut.ply"
    path.write_bytes(data[:-3])
    with pytest.raises(SceneFileError, match="ends inside its face elements"):
        read_ply(path)


@pytest.mark.parametrize(
    "old, new, message",
    [
        ("\n3 6 7 8", "\n3 6 -7 8", "face 4's vertex_indices is -7, not a uint16"),
        ("\n2 4 5", "\n2 4 65536", "face 1's vertex_indices is 65536, not a uint16"),  # an edge, still checked
        ("\n3 6 7 8", "\n3 6 7.5 8", "face 4's vertex_indices is 7.5, not a uint16"),
        ("\n3 6 7 8", "\n3.5 6 7 8", "a list of 3.5 items"),
        ("\n3 6 7 8", "\n-3 6 7 8", "a list of -3 items"),
        ("\n3 6 7 8", "\n3 6 7 x8", "'x8' is not a number"),
    ],
)
def test_ascii_lists_hold_what_their_types_hold(tmp_path, old, new, message):
    text = ply("ascii", MIXED, 0, 0, 0).decode().replace("list uchar int", "list uchar ushort")
    assert old in text
    path = tmp_path / "bad.ply"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(SceneFileError, match=message):
        read_ply(path)


@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian"])
def test_a_large_file_is_read_in_a_few_times_its_size(tmp_path, fmt):
    k = 300
    x, y = np.meshgrid(np.arange(k), np.arange(k))
    vertices = np.stack([x.ravel() * 0.01, y.ravel() * 0.01, np.sin(x.ravel() * 0.1)], 1).astype(np.float32)
    i = (y[:-1, :-1] * k + x[:-1, :-1]).ravel()
    faces = np.concatenate([np.stack([i, i + 1, i + k], 1), np.stack([i + 1, i + k + 1, i + k], 1)])
    head = f"ply\nformat {fmt} 1.0\nelement vertex {len(vertices)}\nproperty float x\nproperty float y\n"
    head += f"property float z\nelement face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    if fmt == "ascii":
        body = "".join(f"{a!r} {b!r} {c!r}\n" for a, b, c in vertices.tolist())
        body += "".join(f"3 {a} {b} {c}\n" for a, b, c in faces.tolist())
        data = (head + body).encode()
    else:
        records = np.zeros(len(faces), [("n", "u1"), ("i", "<i4", (3,))])
        records["n"], records["i"] = 3, faces
        data = head.encode() + vertices.astype("<f4").tobytes() + records.tobytes()
    path = tmp_path / "grid.ply"
    path.write_bytes(data)
    tracemalloc.start()
    try:
        positions, triangles = read_ply(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    np.testing.assert_array_equal(triangles, faces)
    np.testing.assert_array_equal(positions, vertices)
    assert peak < 6 * len(data), (peak, len(data))  # 4.2 times (ASCII), 4.3 (binary); as tuples: 11, 14
