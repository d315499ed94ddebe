"""ASCII STL read by its writers' layout (stl_reader._as_written: words split a piece at a time)
against the exact path (the patterns that read any whitespace and name each error): the same
vertices bit for bit where the layout's path reads a file, and every other file left to the exact
path, which reads it or refuses it as before."""

import re

import numpy as np
import pytest

from bvhlab._npz import SceneFileError
from bvhlab.library import stl_reader
from bvhlab.library.stl_reader import read_stl

FACET = "facet normal {n}\n  outer loop\n{v}  endloop\nendfacet\n"
NUMBERS = ["0", "-0", "+1.5", "1E5", "2.5e-3", "-.75", "7.", "nan", "inf", "-Infinity", "1e400", "3.4028236e38"]


def facets(count: int, seed: int = 5, fmt: str = "{:.9g}") -> str:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        v = "".join("    vertex " + " ".join(fmt.format(x) for x in rng.normal(size=3) * 10) + "\n" for _ in range(3))
        out.append(FACET.format(n="0 0 1", v=v))
    return "".join(out)


def exact(path, monkeypatch):
    """read_stl by the exact path alone."""
    with monkeypatch.context() as m:
        m.setattr(stl_reader, "_as_written", lambda text: None)
        return read_stl(path)


def write(tmp_path, text: str | bytes):
    path = tmp_path / "t.stl"
    path.write_bytes(text.encode() if isinstance(text, str) else text)
    return path


def test_a_solid_after_many_blank_lines_is_read(tmp_path, monkeypatch):
    """The review's: the next solid was looked for in the 64 bytes after an `endsolid` line, and a
    file whose second solid came after more blank lines lost it without an error."""
    text = "solid a\n" + facets(2) + "endsolid a\n" + "\r\n" * 100 + "  solid b\n" + facets(3, 9) + "endsolid b"
    path = write(tmp_path, text)
    vertices = stl_reader._as_written(path.read_bytes())
    assert vertices is not None and len(vertices) == 15
    np.testing.assert_array_equal(vertices.view(np.uint64), exact(path, monkeypatch)[0].view(np.uint64))


def test_endfacet_glued_where_a_piece_ends_is_left_to_the_exact_path(tmp_path, monkeypatch):
    body = facets(6)
    glued = body.replace("endfacet\nfacet", "endfacetfacet", 3)  # the first three facets' ends
    for cut in range(len(glued) - 10, 100, -97):  # pieces ending at many places
        monkeypatch.setattr(stl_reader, "_PIECE", cut)
        path = write(tmp_path, "solid x\n" + glued + "endsolid x\n")
        assert stl_reader._as_written(path.read_bytes()) is None, cut
    with pytest.raises(SceneFileError, match="facet 1 has 12 vertices, not three"):
        read_stl(path)


@pytest.mark.parametrize("piece", [1 << 22, 700])  # pieces cut between facets many times over
def test_the_writers_layout_gives_the_exact_paths_vertices(tmp_path, monkeypatch, piece):
    odd = "".join(
        FACET.format(n="-0 nan 1", v="".join(f"vertex {a} {b} {c}\n" for a, b, c in [NUMBERS[k : k + 3]] * 3))
        for k in range(0, len(NUMBERS), 3)
    )
    body = facets(300) + odd + facets(200, seed=6, fmt="{:e}")
    more = "solid a\n" + facets(100, 7) + "endsolid a\n\n" + "SOLID B\n" + facets(150, 8).upper() + "ENDSOLID B\n"
    for text in (
        "solid my_part\n" + body + "endsolid my_part\n",
        ("solid\n" + body + "endsolid").replace("\n", "\r\n"),
        "solid my_part\n" + body + "endsolid my_part\n" + more,  # three solids (CAD bodies), one in upper case
        "solid endsolid\n" + body + "endsolid endsolid\n",  # the name is no end: looked for after its line
    ):
        path = write(tmp_path, text.replace("    vertex", "\tvertex  "))
        monkeypatch.setattr(stl_reader, "_PIECE", piece)
        assert stl_reader._as_written(path.read_bytes()) is not None  # the layout's path read it
        vertices, triangles = read_stl(path)
        want, want_triangles = exact(path, monkeypatch)
        assert len(vertices) == 3 * (500 + len(NUMBERS) // 3 + (250 if "SOLID B" in text else 0))
        np.testing.assert_array_equal(vertices.view(np.uint64), want.view(np.uint64))  # NaN, -0 and inf too
        np.testing.assert_array_equal(triangles, want_triangles)


LEFT_TO_THE_EXACT_PATH = {
    "keywords in mixed case": ("solid x\n" + facets(2).replace("endfacet", "EndFacet") + "endsolid x\n", None),
    "a name that says facet": ("solid facet maker\n" + facets(2) + "endsolid facet maker\n", None),
    "facets on the solid's line": ("solid x " + facets(2).replace("\n", " ") + "endsolid x\n", None),
    "two solids on a line": ("solid a\n" + facets(2) + "endsolid a solid b\n" + facets(1) + "endsolid b\n", None),
    # the review's: a solid after 64 blank bytes was dropped, and names that say `vertex` on lines
    # the exact path does not take for a solid's were read
    "a vertex after blank lines": ("solid a\n" + facets(2) + "endsolid a\n" + "\n" * 70 + "vertex 1 2 3\n",
                                   "after the last endfacet"),
    "a name after a form feed": ("solid a\n" + facets(2) + "endsolid a\n\x0csolid vertex colors\n" + facets(1)
                                 + "endsolid b\n", "not 'vertex x y z'"),
    "a name after a lone CR": ("solid a\rvertex 1 2 3\n" + facets(2) + "endsolid a\n", "after the last|not 'vertex"),
    "endsolid on endfacet's line": ("solid a\n" + facets(2).rstrip() + " endsolid vertex colors\n",
                                    "not 'vertex x y z'"),
    "solidx": ("solid a\n" + facets(1) + "endsolid a\nsolidx vertex 1 2 3\n" + facets(1) + "endsolid b\n",
               "not 'vertex x y z'"),
    # a bare ValueError before (the review's)
    "nanx": ("solid x\n" + re.sub("vertex \\S+", "vertex nanx", facets(2), count=1) + "endsolid x\n",
             "not 'vertex x y z'"),
    "words between solids": (
        "solid a\n" + facets(2) + "endsolid a\nvertex 1 2 3\nsolid b\n" + facets(1) + "endsolid b\n",
        "after the last endfacet|not 'vertex|vertices",
    ),
    "no endsolid": ("solid x\n" + facets(2), None),
    "a normal of words": ("solid x\n" + facets(2).replace("normal 0 0 1", "normal a b c") + "endsolid x\n", None),
    "an underscore in a number": ("solid x\n" + facets(2).replace("vertex ", "vertex 1_0", 1) + "endsolid x\n",
                                  "not 'vertex x y z'"),
    "a long number": ("solid x\n" + facets(1).replace("vertex ", "vertex " + "1" * 100 + " ", 1) + "endsolid x\n",
                      "not 'vertex x y z'"),
    "a long word": ("solid x\n" + facets(2).replace("outer", "x" * (1 << 20) + " outer", 1) + "endsolid x\n", None),
    # a review's cases: `endfacet` glued to the next word, a vertex after `endsolid`, NUL bytes
    "endfacetendsolid": ("solid x\n" + facets(2)[:-1] + "endsolid x\n", "after the last endfacet"),
    "a vertex after endsolid": ("solid x\n" + facets(2) + "endsolid x\nvertex 1 2 3\n", "after the last endfacet"),
    "a NUL after a number": (
        "solid x\n" + FACET.format(n="0 0 1", v="vertex 1\0 2 3\nvertex 4 5 6\nvertex 7 8 9\n") + "endsolid x\n",
        "not 'vertex x y z'",
    ),
    "a NUL after a keyword": ("solid x\n" + facets(2).replace("endloop", "endloop\0", 1) + "endsolid x\n",
                              "not 'vertex x y z'|facet"),
    "four numbers": ("solid x\n" + facets(2).replace("vertex ", "vertex 7 ", 1) + "endsolid x\n", "not 'vertex x y z'"),
    "four vertices": ("solid x\n" + facets(2).replace("endloop", "vertex 0 0 0\nendloop", 1) + "endsolid x\n",
                      "facet 1 has 4 vertices"),
    "a word for a number": ("solid x\n" + facets(2).replace("vertex ", "vertex 1e5x ", 1) + "endsolid x\n",
                            "not 'vertex x y z'"),
}  # fmt: skip


@pytest.mark.parametrize("piece", [1 << 22, 300])
@pytest.mark.parametrize("case", LEFT_TO_THE_EXACT_PATH)
def test_other_files_are_left_to_the_exact_path(tmp_path, monkeypatch, case, piece):
    """Each file as it is, its pieces cut where the file is whole or a few facets apart (a facet's
    `endfacet` glued to the next facet where a piece ends was read: the review's case)."""
    text, message = LEFT_TO_THE_EXACT_PATH[case]
    monkeypatch.setattr(stl_reader, "_PIECE", piece)
    path = write(tmp_path, text)
    assert stl_reader._as_written(path.read_bytes()) is None
    if message is None:
        vertices, _ = read_stl(path)
        np.testing.assert_array_equal(vertices.view(np.uint64), exact(path, monkeypatch)[0].view(np.uint64))
        assert len(vertices) % 3 == 0 and len(vertices) >= 3
    else:
        with pytest.raises(SceneFileError, match=message):
            read_stl(path)
