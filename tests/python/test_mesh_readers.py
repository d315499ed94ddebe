"""bvhlab's own OBJ, PLY and STL readers, on files written here by hand, each against figures
computed here (triangle counts, areas by the shoelace formula, positions): the cases trimesh read
wrong or refused (a probe of real files: Blender's binary PLY of a mesh of triangles and quads,
OBJ's relative indices, a concave polygon). The glTF checks: test_gltf_files.py; polygons into
triangles: test_polygon_files.py."""

import struct

import numpy as np
import pytest

from bvhlab._npz import SceneFileError
from bvhlab.library.files import load_mesh_file


def area(triangles: np.ndarray) -> float:
    t = np.asarray(triangles, np.float64)
    return float(0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum())


def load(tmp_path, name: str, data) -> np.ndarray:
    path = tmp_path / name
    path.write_bytes(data.encode() if isinstance(data, str) else data)
    return load_mesh_file(path).triangles


# a concave pentagon (an arrow head): shoelace area 2.5; a fan from its first corner covers 3.5
CONCAVE = [(0, 0, 0), (2, 0, 0), (2, 2, 0), (1, 0.5, 0), (0, 2, 0)]
CONCAVE_AREA = 0.5 * abs(sum(x0 * y1 - x1 * y0 for (x0, y0, _), (x1, y1, _) in zip(CONCAVE, CONCAVE[1:] + CONCAVE[:1])))


def test_concave_polygon_keeps_its_shape_in_obj_and_ply(tmp_path):
    assert CONCAVE_AREA == 2.5
    vertices = "".join(f"v {x} {y} {z}\n" for x, y, z in CONCAVE)
    obj = load(tmp_path, "arrow.obj", vertices + "f 1 2 3 4 5\n")
    assert len(obj) == 3 and area(obj) == pytest.approx(2.5)
    # the same polygon starting at its reflex corner, and as a concave quad
    obj = load(tmp_path, "arrow2.obj", vertices + "f 4 5 1 2 3\n")
    assert area(obj) == pytest.approx(2.5)
    quad = load(tmp_path, "dart.obj", "v 0 0 0\nv 2 0 0\nv 0.5 0.5 0\nv 0 2 0\nf 1 2 3 4\nf 2 3 4 1\n")
    assert area(quad) == pytest.approx(2 * 1.0)  # the dart's area: 2 × (0.5·2·0.5) each way round
    ply = ply_ascii(CONCAVE, [[0, 1, 2, 3, 4]])
    assert area(load(tmp_path, "arrow.ply", ply)) == pytest.approx(2.5)


def test_obj_relative_indices_count_back_from_the_vertices_so_far(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nv 6 5 5\nv 6 6 5\nf -3 -2 -1\nf 1 -2 -1\n"
    t = load(tmp_path, "rel.obj", text)
    np.testing.assert_array_equal(t[0], [(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    np.testing.assert_array_equal(t[1], [(5, 5, 5), (6, 5, 5), (6, 6, 5)])
    np.testing.assert_array_equal(t[2], [(0, 0, 0), (6, 5, 5), (6, 6, 5)])


def test_obj_as_people_write_it(tmp_path):
    # tabs, comments at line ends, a continued line, CRLF, a byte-order mark, v/vt/vn corners
    # and a face naming vertices defined after it
    text = (
        "\ufeff# made by hand\r\nf 1/1/1 2//1 3/2\r\nv\t0 0 0 # origin\r\nv 1 0\\\r\n 0\r\n"
        "v 0 1 0 1.0\r\nvt 0 0\r\nvn 0 0 1\r\nv  0  0  2\r\nf 1 2 4\r\n"
    )
    t = load(tmp_path, "odd.obj", text)
    np.testing.assert_array_equal(t[0], [(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    np.testing.assert_array_equal(t[1], [(0, 0, 0), (1, 0, 0), (0, 0, 2)])


@pytest.mark.parametrize(
    "text, message",
    [
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4: vertex index 0"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 -2 -1\n", "line 4: vertex -4 does not exist"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4: vertex 4 does not exist"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "line 4: 'f 1 2 x' is not vertex indices"),
        ("v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", "vertex 2 needs x, y and z"),
        ("v 0 0 0\nv 1,5 0 0\nv 0 1 0\nf 1 2 3\n", "not a number"),
        ("v 0 0 0\nv 1_0 0 0\nv 0 1 0\nf 1 2 3\n", "a vertex coordinate: '1_0' is not a number"),  # was x = 10
        ("v 0 0 0\nv \uff11 0 0\nv 0 1 0\nf 1 2 3\n", "'\uff11' is not a number"),  # fullwidth 1: was x = 1
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n", "line 4: vertex 99999999999999999999 does not"),
    ],
)
def test_obj_errors_name_the_line(tmp_path, text, message):
    with pytest.raises(SceneFileError, match=message):
        load(tmp_path, "bad.obj", text)


def ply_ascii(vertices, faces, extra: str = "") -> str:
    head = f"ply\nformat ascii 1.0\nelement vertex {len(vertices)}\nproperty float x\nproperty float y\n"
    head += f"property float z\nelement face {len(faces)}\nproperty list uchar int vertex_indices\n{extra}end_header\n"
    body = "".join(f"{x} {y} {z}\n" for x, y, z in vertices)
    return head + body + "".join(f"{len(f)} {' '.join(map(str, f))}\n" for f in faces)


def ply_binary(vertices, faces, order: str, count: str = "B", index: str = "i") -> bytes:
    fmt = "binary_little_endian" if order == "<" else "binary_big_endian"
    names = {"B": "uchar", "H": "ushort", "i": "int", "I": "uint"}
    head = (
        f"ply\nformat {fmt} 1.0\ncomment a mesh of triangles and quads, as Blender writes it\n"
        f"element vertex {len(vertices)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"property uchar red\nelement face {len(faces)}\n"
        f"property list {names[count]} {names[index]} vertex_indices\nelement edge 1\nproperty int vertex1\n"
        "property int vertex2\nend_header\n"
    ).encode()
    body = b"".join(struct.pack(order + "fffB", *v, 7) for v in vertices)
    body += b"".join(struct.pack(f"{order}{count}{len(f)}{index}", len(f), *f) for f in faces)
    return head + body + struct.pack(order + "ii", 0, 1)


CUBE = [(x, y, z) for x in (0, 1) for y in (0, 2) for z in (0, 3)]  # corners: index = 4x + 2y' + z'
MIXED = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7], [2, 7, 3]]  # quads and two triangles
MIXED_AREA = 2 * 1 + 2 * 1 + 1 * 3 + 1 * 3  # two 1×2 faces, a 1×3 face, a 1×3 face in two triangles


@pytest.mark.parametrize("order", ["<", ">"])
@pytest.mark.parametrize("count, index", [("B", "i"), ("B", "I"), ("H", "i")])
def test_binary_ply_of_triangles_and_quads(tmp_path, order, count, index):
    t = load(tmp_path, "mixed.ply", ply_binary(CUBE, MIXED, order, count, index))
    assert len(t) == 8 and area(t) == pytest.approx(MIXED_AREA)
    assert set(map(tuple, t.reshape(-1, 3).tolist())) <= set(CUBE)


@pytest.mark.parametrize(
    "data, message",
    [
        (ply_binary(CUBE, MIXED, "<")[:-3], "ends inside its edge elements"),
        (ply_binary(CUBE, MIXED, "<") + b"\0" * 5, "5 bytes after the elements"),
        (ply_ascii(CUBE, MIXED)[: -len("3 2 7 3\n")], "ends inside its face elements"),
        (ply_ascii(CUBE, MIXED) + "3 0 1 2\n", "4 values after the elements"),
        (ply_ascii(CUBE, [[0, 1, 99]]), "face 0 refers to a vertex that does not exist"),
    ],
)
def test_ply_whose_header_lies_is_refused(tmp_path, data, message):
    with pytest.raises(SceneFileError, match=message):
        load(tmp_path, "lies.ply", data)


@pytest.mark.parametrize("lead", [b"SOLID", b"\xef\xbb\xbfsolid", b"  Solid"])
def test_ascii_stl_in_any_case_or_after_a_byte_order_mark(tmp_path, lead):
    text = lead + b" x\nfacet normal 0 0 1\nouter loop\nVERTEX 0 0 0\nvertex 1 0 0\nvertex 0 1 1e0\nendloop\nendfacet\n"
    t = load(tmp_path, "upper.stl", text + b"endsolid x\n")
    np.testing.assert_array_equal(t[0], [(0, 0, 0), (1, 0, 0), (0, 1, 1)])


def test_binary_stl_whose_header_starts_with_solid(tmp_path):
    body = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
    t = load(tmp_path, "solid.stl", b"solid by some exporter".ljust(80, b" ") + struct.pack("<I", 1) + body)
    np.testing.assert_array_equal(t[0], [(0, 0, 0), (1, 0, 0), (0, 1, 0)])


@pytest.mark.parametrize(
    "text, triangles",
    [
        ("f 1 2 3 # note\u2028f 2 4 3\n", 1),  # a line separator inside a comment: not a line end
        ("f 1 2 3 # note\u0085f 2 4 3\n", 1),
        ("f 1 2 3\v4\n", 2),  # a vertical tab between corners: a space
        ("f 1 2\u00a04 3\n", 2),  # a no-break space likewise
        ("f 1 2 \\  \n 4 3\n", 2),  # a continued line, spaces after the backslash
        ("f 1 2 3\rf 2 4 3\r", 2),  # old Mac line ends
    ],
)
def test_obj_line_ends_and_spaces(tmp_path, text, triangles):
    t = load(tmp_path, "ends.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n" + text)
    assert len(t) == triangles


@pytest.mark.parametrize(
    "data, message",
    [
        (ply_ascii(CUBE, MIXED).replace("ply\n", "ply\ncomment no end_header here\n", 1), None),
        (ply_ascii(CUBE, MIXED).replace("property list uchar int vertex_indices", "property int vertex_indices"),
         "must be a list of integers|values after the elements"),
        (ply_ascii(CUBE, MIXED).replace("list uchar int", "list uchar float"), None),  # whole numbers: indices
        (ply_ascii(CUBE, MIXED).replace("\n1 0 0\n", "\n1_0 0 0\n", 1), "'1_0' is not a number"),  # was x = 10
        (ply_binary(CUBE, MIXED, "<").replace(b"list uchar int", b"list float int"),
         "a binary list's length must have an integer type"),  # was "ends inside its face elements"
        (ply_ascii(CUBE, [[0, 1, 2]]).replace("list uchar int", "list uchar float").replace("3 0 1 2", "3 0 1 2.5"),
         "not indices"),
        (ply_ascii(CUBE, MIXED).replace("end_header", " end_header"), None),
        # a texture-coordinate list of floats beside the indices (MeshLab writes one)
        (ply_ascii(CUBE, [[0, 4, 6, 2]], "property list uchar float texcoord\n")
         .replace("0 4 6 2\n", "0 4 6 2 2 0.5 0.25\n"), None),
    ],
)  # fmt: skip
def test_ply_header_words_in_comments_and_face_types(tmp_path, data, message):
    if message is None:
        assert area(load(tmp_path, "c.ply", data)) in (pytest.approx(MIXED_AREA), pytest.approx(2.0))
    else:
        with pytest.raises(SceneFileError, match=message):
            load(tmp_path, "c.ply", data)


def test_ascii_stl_whose_name_says_vertex(tmp_path):
    text = "solid vertex colors\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
    assert len(load(tmp_path, "named.stl", text + "endloop\nendfacet\nendsolid vertex colors\n")) == 1


def test_ascii_stl_facets_on_one_line(tmp_path):
    """STL is whitespace-separated: a facet written on one line (a probe's file was refused as "no
    vertex lines ... as binary STL its header declares 1886351212 triangles"), under a name that
    says "facet vertex" (a name is free text to its line's end); a file cut in a vertex is refused
    (the review: reading up to the last `endfacet` dropped its last facet silently)."""
    facet = "facet normal 0 0 1 outer loop vertex 0 0 0 vertex {} 0 0 vertex 0 1 0 endloop endfacet"
    lines = "solid facet vertex colors\n" + facet.format(1) + "\n" + facet.format(2) + "\nendsolid facet vertex\n"
    assert area(load(tmp_path, "lines.stl", lines)) == pytest.approx(1.5)
    for name in ("t ", ""):  # the whole file on one line (probe): its solid's line held every facet
        one = f"solid {name}{facet.format(1)} {facet.format(2)} endsolid {name}"
        assert area(load(tmp_path, "one.stl", one)) == pytest.approx(1.5)
        first = f"solid {name}{facet.format(1)}\n{facet.format(2)}\nendsolid {name}"  # and the first facet only
        assert area(load(tmp_path, "first.stl", first)) == pytest.approx(1.5)
    with pytest.raises(SceneFileError, match="not 'vertex x y z'"):
        cut = "\nfacet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0"
        load(tmp_path, "cut.stl", "solid x\n" + facet.format(1) + cut)


def test_ascii_stl_vertex_lines_are_three_numbers(tmp_path):
    facet = "facet normal 0 0 1\nouter loop\n{}\nendloop\nendfacet\n"
    for lines in ("vertex 0 0 0junk\nvertex 1 0 0\nvertex 0 1 0", "vertex 0 0\nvertex 1 0 0\nvertex 0 1 0"):
        with pytest.raises(SceneFileError, match="not 'vertex x y z'"):
            load(tmp_path, "bad.stl", "solid x\n" + facet.format(lines) + "endsolid x\n")


def test_ascii_stl_facets_of_other_than_three_vertices_are_refused(tmp_path):
    """The probe's cases: a facet of four vertices and one of two were read as two triangles of
    parts of both, and `vertex 0 0 0 7` as the vertex (0, 0, 0), with no error."""
    facet = "facet normal 0 0 1\nouter loop\n{}endloop\nendfacet\n"
    vertex = "vertex {} 0 0\n".format
    four_two = facet.format("".join(vertex(k) for k in range(4))) + facet.format(vertex(5) + vertex(6))
    with pytest.raises(SceneFileError, match="facet 1 has 4 vertices, not three"):
        load(tmp_path, "a.stl", "solid x\n" + four_two + "endsolid x\n")
    with pytest.raises(SceneFileError, match="not 'vertex x y z'"):
        load(tmp_path, "b.stl", "solid x\n" + facet.format("vertex 0 0 0 7\n" + vertex(1) + vertex(2)))
    with pytest.raises(SceneFileError, match="after the last endfacet"):
        load(tmp_path, "c.stl", "solid x\n" + facet.format(vertex(0) + vertex(1) + vertex(2)) + vertex(3))


UTF16_TEXTS = {
    "obj": "# exported\nv 0 0 0\nv 2 0 0\nv 0 3 0\nf 1 2 3\n",
    "stl": "solid tri\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 2 0 0\nvertex 0 3 0\nendloop\n"
    "endfacet\nendsolid tri\n",
    "ply": "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n2 0 0\n0 3 0\n3 0 1 2\n",
}


@pytest.mark.parametrize("codec", ["utf-16", "utf-16-be"])
@pytest.mark.parametrize("kind", sorted(UTF16_TEXTS))
def test_text_files_saved_as_utf16_read_as_utf8(tmp_path, kind, codec):
    """Notepad's "Unicode" and PowerShell 5's `>` write UTF-16 with a byte-order mark: the OBJ read
    as "0 faces", the STL and PLY as not STL or PLY."""
    text = UTF16_TEXTS[kind]
    data = text.encode(codec) if codec == "utf-16" else b"\xfe\xff" + text.encode(codec)
    assert data[:2] in (b"\xff\xfe", b"\xfe\xff")
    got = load(tmp_path, f"tri.{kind}", data)
    np.testing.assert_array_equal(got, load(tmp_path, f"utf8.{kind}", text))
    assert got.tolist() == [[[0, 0, 0], [2, 0, 0], [0, 3, 0]]]


@pytest.mark.parametrize("kind", sorted(UTF16_TEXTS))
def test_text_files_with_a_utf8_byte_order_mark(tmp_path, kind):
    """Notepad's "UTF-8 with BOM": the PLY was "not a PLY file" (probe); OBJ and STL read it."""
    text = UTF16_TEXTS[kind]
    got = load(tmp_path, f"bom.{kind}", b"\xef\xbb\xbf" + text.encode())
    assert got.tolist() == [[[0, 0, 0], [2, 0, 0], [0, 3, 0]]]


def test_ply_magic_line_and_long_header(tmp_path):
    """The probe's cases: a first line "plyx" was read as PLY; a header longer than the reader
    looks (64 KiB of comments) was called "not a PLY file"."""
    text = UTF16_TEXTS["ply"]
    with pytest.raises(SceneFileError, match="its first line is not 'ply'"):
        load(tmp_path, "x.ply", text.replace("ply\n", "plyx\n", 1))
    long = text.replace("ply\n", "ply\n" + "comment padding\n" * 5000, 1)
    with pytest.raises(SceneFileError, match="no 'end_header' line in its first 64 KiB"):
        load(tmp_path, "long.ply", long)


@pytest.mark.parametrize(
    "name, data, message",
    [
        ("no_mark.obj", UTF16_TEXTS["obj"].encode("utf-16-le"), "a NUL byte at byte 1, which OBJ text has not"),
        ("nul.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\x00\n", "a NUL byte at byte 31"),
        ("half.obj", b"\xff\xfev\x00 \x00\x00\xd8", "a UTF-16 byte-order mark but is not UTF-16"),
        ("half.stl", b"\xff\xfes\x00\x00\xdc", "a UTF-16 byte-order mark but is not UTF-16"),
    ],
)
def test_text_files_that_are_not_utf8_or_utf16_say_so(tmp_path, name, data, message):
    with pytest.raises(SceneFileError, match=message):
        load(tmp_path, name, data)


def test_a_polygon_with_corners_beyond_float_range_is_refused_by_the_vertex_check(tmp_path):
    """Corners at ±1e308 overflowed the grid's span: "cannot convert float NaN to integer" rather
    than the reader's own message (review)."""
    path = tmp_path / "big.obj"
    corners = [(1e308, 0), (0.5e308, 1e308), (-0.5e308, 1e308), (-1e308, 0), (-0.5e308, -1e308), (0.5e308, -2)]
    path.write_text("".join(f"v {x!r} {y!r} 0\n" for x, y in corners) + "f 1 2 3 4 5 6\n")
    with pytest.raises(SceneFileError, match="NaN, infinite or out-of-range vertex"):
        load_mesh_file(path)


@pytest.mark.parametrize(
    "header, message",
    [
        ("element face 1\nproperty list uchar int vertex_indices\n" * 2, "2 elements named 'face'"),
        (
            "element face 1\nproperty list uchar int vertex_indices\nproperty list uchar int vertex_indices\n",
            "2 properties named 'vertex_indices'",
        ),
    ],
)
def test_ply_names_declared_twice_are_refused(tmp_path, header, message):
    """A probe's case: a second `element face` replaced the first's faces (one of two triangles read)."""
    text = (
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        + header
        + "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n"
    )
    with pytest.raises(SceneFileError, match=message):
        load(tmp_path, "twice.ply", text)


def test_ascii_stl_of_long_numbers_is_refused_at_once(tmp_path):
    """A probe's case: three 160-digit numbers and a letter on a vertex line took 38 s to refuse
    (the number pattern split a run of digits many ways); 2,000 digits took far longer. Read in a
    child process, so that a return of the backtracking fails this test instead of hanging it."""
    import subprocess
    import sys

    d = "1" * 2000
    path = tmp_path / "long.stl"
    path.write_text(f"solid t\nfacet normal 0 0 1\nouter loop\nvertex {d} {d} {d}x\nendloop\nendfacet\nendsolid t\n")
    code = (
        "import sys\nfrom bvhlab.library.files import load_mesh_file\n"
        "try:\n    load_mesh_file(sys.argv[1])\nexcept Exception as e:\n    print(type(e).__name__, e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, timeout=120)
    assert "not 'vertex x y z'" in out.stdout, out.stdout + out.stderr


def test_ascii_stl_of_a_long_run_of_blanks_is_refused_at_once(tmp_path):
    """A helper's audit: a line of blanks not followed by "solid" was tried at every split around
    an optional byte-order mark (20 KB of spaces 6.7 s, 4 MB hours); 4 MB is refused in under a
    second now. In a child process, as the case above, so that a return of it fails, not hangs."""
    import subprocess
    import sys

    path = tmp_path / "blanks.stl"
    path.write_bytes(b"solid x\n" + b" \t" * 2_000_000 + b"x\nendsolid x\n")
    code = (
        "import sys\nfrom bvhlab.library.files import load_mesh_file\n"
        "try:\n    load_mesh_file(sys.argv[1])\nexcept Exception as e:\n    print(type(e).__name__, e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, timeout=120)
    assert "no facets" in out.stdout, out.stdout + out.stderr


@pytest.mark.parametrize(
    "header, message",
    [
        ("format ascii 1.0\nformat binary_little_endian 1.0\n", "two 'format' lines"),  # read as "truncated"
        ("format ascii 2.0\n", "PLY version '2.0'; bvhlab reads version 1.0"),  # read as 1.0
    ],
)
def test_ply_format_lines_are_checked(tmp_path, header, message):
    text = "ply\n" + header + "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    text += "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
    with pytest.raises(SceneFileError, match=message):
        load(tmp_path, "model.ply", text)


@pytest.mark.parametrize("kind, value", [("uchar", "-1000"), ("uchar", "256"), ("int", "0.5"), ("char", "128")])
def test_ply_ascii_values_outside_their_declared_type_are_refused(tmp_path, kind, value):
    """`uchar x` of -1000 and `int x` of 0.5 were read as written (a helper's audit)."""
    text = f"ply\nformat ascii 1.0\nelement vertex 3\nproperty {kind} x\nproperty float y\nproperty float z\n"
    text += f"element face 1\nproperty list uchar int vertex_indices\nend_header\n{value} 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
    with pytest.raises(SceneFileError, match=rf"vertex 0's x is {value}, not a"):
        load(tmp_path, "model.ply", text)


def test_ply_names_it_does_not_read_may_repeat(tmp_path):
    """The review's case: names the reader skips (a second `element edge`, a repeated `property
    uchar red`) were read right before the refusal of names declared twice, and still are."""
    text = (
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "property uchar red\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\n"
        "element edge 1\nproperty int a\nelement edge 1\nproperty int a\n"
        "end_header\n0 0 0 1 1\n1 0 0 1 1\n0 1 0 1 1\n3 0 1 2\n7\n8\n"
    )
    t = load(tmp_path, "ok.ply", text)
    np.testing.assert_array_equal(t, [[(0, 0, 0), (1, 0, 0), (0, 1, 0)]])
