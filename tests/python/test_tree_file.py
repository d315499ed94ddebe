"""Bvh.save and bvhlab.load_bvh (issue 35): save → load gives the same nodes, stats and hits; a
file cut short, damaged, of another version, for other geometry or other settings is refused
with a clear error; nodes that are not a tree are refused by the core's checks, never a crash."""

import hashlib
import json
import struct

import numpy as np
import pytest

import bvhlab
from bvhlab.inspect import tree_file
from bvhlab.library import procedural, showcase


@pytest.fixture()
def saved(tmp_path, small_scene):
    tris, spheres = small_scene
    bvh = bvhlab.build(tris, spheres, method="sah", bins=16, max_leaf_size=3)
    path = tmp_path / "tree.bvhtree"
    bvh.save(path)
    return bvh, path, tris, spheres


def test_round_trip(saved):
    bvh, path, tris, spheres = saved
    loaded = bvhlab.load_bvh(path, tris, spheres)
    np.testing.assert_array_equal(loaded.nodes, bvh.nodes)
    np.testing.assert_array_equal(loaded.refs, bvh.refs)
    np.testing.assert_array_equal(loaded.depths, bvh.depths)
    assert loaded.config == bvh.config
    assert loaded.stats == bvh.stats  # build_ms included: the saved build's
    origins, dirs = procedural.random_rays(tris, 500, seed=2)
    for traversal in bvhlab.TRAVERSALS:
        a, b = bvh.intersect(origins, dirs, traversal=traversal), loaded.intersect(origins, dirs, traversal=traversal)
        for key in a:
            np.testing.assert_array_equal(a[key], b[key])
    np.testing.assert_array_equal(loaded.node_data().epo, bvh.node_data().epo)


def test_round_trip_of_a_scene_renders_the_same(tmp_path):
    scene = showcase.whitted()
    bvh = bvhlab.build(scene, method="median")
    bvh.save(tmp_path / "w.bvhtree")
    loaded = bvhlab.load_bvh(tmp_path / "w.bvhtree", scene, config=bvhlab.BuildConfig(method="median"))
    a, _ = bvhlab.render(scene, bvh, 32, 24, backend="cpu")
    b, _ = bvhlab.render(scene, loaded, 32, 24, backend="cpu")
    np.testing.assert_array_equal(a, b)


def test_save_needs_the_suffix_and_overwrites_nothing_else(tmp_path, small_scene):
    """`Bvh.save` writes only a .bvhtree: a scene's .npz (or any other name) is refused before
    anything is written, and the file already there is left as it was (it used to be replaced)."""
    tris, spheres = small_scene
    scene_file = bvhlab.Scene(triangles=tris, spheres=spheres).save(tmp_path / "scene.npz")
    before = scene_file.read_bytes()
    bvh = bvhlab.build(tris, spheres)
    for name in ("scene.npz", "tree.txt", "tree", ".bvhtree"):
        with pytest.raises(OSError, match="tree file|no stem"):
            bvh.save(tmp_path / name)
    assert scene_file.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.npz"]
    with pytest.raises(OSError, match="is a folder"):
        bvh.save(tmp_path)
    assert bvh.save(tmp_path / "Tree.BVHTREE") is None  # any case of the suffix, as for scene files
    assert bvhlab.load_bvh(tmp_path / "Tree.BVHTREE", tris, spheres).stats == bvh.stats


def test_empty_tree(tmp_path):
    tris = np.zeros((0, 3, 3), np.float32)
    bvhlab.build(tris).save(tmp_path / "e.bvhtree")
    assert bvhlab.load_bvh(tmp_path / "e.bvhtree", tris).stats["nodes"] == 0


def test_cut_short_or_damaged(saved):
    _, path, tris, spheres = saved
    data = path.read_bytes()
    for cut in (5, 20, len(data) // 2, len(data) - 1):
        path.write_bytes(data[:cut])
        with pytest.raises(tree_file.TreeFileError, match="not a bvhlab tree file|cut short"):
            bvhlab.load_bvh(path, tris, spheres)
    damaged = bytearray(data)
    damaged[len(data) // 2] ^= 0x40
    path.write_bytes(bytes(damaged))
    with pytest.raises(ValueError, match="damaged"):
        bvhlab.load_bvh(path, tris, spheres)
    path.write_bytes(b"PK\x03\x04 not a tree")
    with pytest.raises(ValueError, match="not a bvhlab tree file"):
        bvhlab.load_bvh(path, tris, spheres)


def test_other_version(saved):
    _, path, tris, spheres = saved
    data = bytearray(path.read_bytes())
    struct.pack_into("<I", data, len(tree_file.MAGIC), tree_file.FORMAT_VERSION + 1)
    path.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=f"version {tree_file.FORMAT_VERSION + 1}; this bvhlab reads version 1"):
        bvhlab.load_bvh(path, tris, spheres)


def test_other_geometry(saved):
    _, path, tris, spheres = saved
    with pytest.raises(ValueError, match="other geometry: 400 triangles and 60 spheres"):
        bvhlab.load_bvh(path, tris[:-1], spheres)
    moved = tris.copy()
    moved[7, 1, 2] += 1e-3  # same counts, one vertex moved: the fingerprint tells
    with pytest.raises(ValueError, match="saved for other geometry .its fingerprint"):
        bvhlab.load_bvh(path, moved, spheres)


def test_other_settings(saved):
    _, path, tris, spheres = saved
    with pytest.raises(ValueError, match="built with method=sah, bins=16.*not with method=median"):
        bvhlab.load_bvh(path, tris, spheres, config=bvhlab.BuildConfig(method="median"))
    ok = bvhlab.BuildConfig(method="sah", bins=16, max_leaf_size=3, threads=1)  # threads never change a tree
    assert bvhlab.load_bvh(path, tris, spheres, config=ok).config.bins == 16


def _rewrite(path, change):
    """The file with its nodes changed by `change(nodes)` and a checksum that fits again: what a
    hostile or buggy writer could make."""
    data = path.read_bytes()
    start = len(tree_file.MAGIC) + 8
    head_len = struct.unpack_from("<I", data, len(tree_file.MAGIC) + 4)[0]
    header_end = start + head_len
    n = json.loads(data[start:header_end])["nodes"]
    nodes = np.frombuffer(data, bvhlab.NODE_DTYPE, n, header_end).copy()
    change(nodes)
    body = data[:header_end] + nodes.tobytes() + data[header_end + 32 * n : -32]
    path.write_bytes(body + hashlib.sha256(body).digest())


def _set(field, node, value):
    def change(nodes):
        nodes[field][node] = value(nodes) if callable(value) else value

    return change


@pytest.mark.parametrize(
    "change, message",
    [
        (_set("index", 0, 10**6), "child out of order or range"),
        (_set("info", 0, lambda n: n["info"][0] ^ 1), "skip index|second child"),
        (_set("index", 0, 1), "child out of order or range"),  # the second child is the first
        (_set("lo", 5, np.float32(np.nan)), "not finite"),
        (_set("hi", 0, lambda n: n["hi"][0] - 0.5), "does not hold its children"),
        (_set("lo", -1, lambda n: n["hi"][-1]), "does not hold its primitives"),
    ],
)
def test_nodes_that_are_not_a_tree_are_refused(saved, change, message):
    _, path, tris, spheres = saved
    _rewrite(path, change)
    with pytest.raises(ValueError, match=message):
        bvhlab.load_bvh(path, tris, spheres)


def test_leaf_slots_out_of_range_are_refused(saved):
    _, path, tris, spheres = saved

    def change(nodes):
        leaf = np.nonzero((nodes["info"] & bvhlab.bvh.NODE_INTERNAL_BIT) == 0)[0][-1]
        nodes["info"][leaf] = 2**31 - 1  # a huge leaf: slots far past the references

    _rewrite(path, change)
    with pytest.raises(ValueError, match="wrong slots|every reference"):
        bvhlab.load_bvh(path, tris, spheres)


def test_save_is_atomic(saved, monkeypatch):
    """Ctrl-C half-way through a save: the old file stays whole and no temporary is left."""
    bvh, path, tris, spheres = saved
    before = path.read_bytes()
    real = hashlib.sha256

    class Interrupted:
        def __init__(self):
            self.parts, self.real = 0, real()

        def update(self, part):
            self.parts += 1
            if self.parts == 4:  # after the magic, the version and the header were written
                raise KeyboardInterrupt
            self.real.update(part)

    monkeypatch.setattr(tree_file.hashlib, "sha256", Interrupted)
    with pytest.raises(KeyboardInterrupt):
        bvhlab.build(tris, spheres, method="median").save(path)
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert [p.name for p in path.parent.iterdir()] == [path.name]
    assert bvhlab.load_bvh(path, tris, spheres).config == bvh.config


def _rewrite_header(path, change):
    """The file with its JSON header changed by `change(header)` and a checksum that fits again."""
    data = path.read_bytes()
    start = len(tree_file.MAGIC) + 8
    head_len = struct.unpack_from("<I", data, len(tree_file.MAGIC) + 4)[0]
    header = json.loads(data[start : start + head_len])
    change(header)
    head = json.dumps(header, sort_keys=True).encode()
    prefix = data[: len(tree_file.MAGIC) + 4] + struct.pack("<I", len(head))
    body = prefix + head + data[start + head_len : -32]
    path.write_bytes(body + hashlib.sha256(body).digest())


@pytest.mark.parametrize(
    "key, value",
    [
        ("geometry_fingerprint", 2**70),
        ("geometry_fingerprint", -1),
        ("build_ms", None),
        ("triangles", "100"),
        ("spheres", 1.5),
        ("config", [1, 2]),
    ],  # fmt: skip
)
def test_a_header_field_of_the_wrong_kind_is_a_damaged_header(saved, key, value):
    """A crafted header with a valid checksum: TreeFileError naming the field (a fingerprint of
    2^70 raised nanobind's TypeError, build_ms null a TypeError, triangles "100" said "saved for
    100 triangles, this scene has 100")."""
    _, path, tris, spheres = saved
    _rewrite_header(path, lambda header: header.__setitem__(key, value))
    with pytest.raises(tree_file.TreeFileError, match=f"damaged header.*{key}"):
        bvhlab.load_bvh(path, tris, spheres)


def test_leaves_larger_than_the_headers_max_leaf_size_are_refused(saved):
    """The file says max_leaf_size=1 over a tree with leaves of 3 (every builder, update and
    optimize keeps leaves within the setting): it loaded, also with config= asking for 1, and its
    tables showed a setting the tree does not have (helper probe)."""
    bvh, path, tris, spheres = saved
    assert bvh.stats["max_leaf_size"] == 3
    _rewrite_header(path, lambda header: header["config"].__setitem__("max_leaf_size", 1))
    for config in (None, bvhlab.BuildConfig(method="sah", bins=16, max_leaf_size=1)):
        with pytest.raises(ValueError, match="holds [23] primitives, more than its max_leaf_size 1"):
            bvhlab.load_bvh(path, tris, spheres, config=config)


def test_a_header_of_infinite_or_huge_numbers_or_deep_nesting_is_a_damaged_header(saved):
    """JSON's Infinity and numbers beyond a double raised OverflowError out of load_bvh, a header
    nested 100,000 deep RecursionError (helper probe)."""
    _, path, tris, spheres = saved
    data = path.read_bytes()
    start = len(tree_file.MAGIC) + 8
    head_len = struct.unpack_from("<I", data, len(tree_file.MAGIC) + 4)[0]
    header = json.loads(data[start : start + head_len])
    heads = [
        json.dumps({**header, "nodes": 1}).replace('"nodes": 1', '"nodes": Infinity'),
        json.dumps({**header, "refs": 1}).replace('"refs": 1', '"refs": -Infinity'),
        json.dumps({**header, "nodes": 1}).replace('"nodes": 1', '"nodes": 1e400'),
        json.dumps({**header, "build_ms": 10**400}),
        "[" * 100_000 + "]" * 100_000,
    ]
    for head in heads:
        prefix = data[: len(tree_file.MAGIC) + 4] + struct.pack("<I", len(head))
        body = prefix + head.encode() + data[start + head_len : -32]
        path.write_bytes(body + hashlib.sha256(body).digest())
        with pytest.raises(tree_file.TreeFileError, match="damaged header"):
            bvhlab.load_bvh(path, tris, spheres)


def test_a_file_of_a_scene_too_small_to_trace_is_refused(tmp_path):
    """A tree saved before `build` refused scenes under 2^-32 across (their hits were lost: the
    triangle test's products underflow) is refused on load as build refuses it. The file is the
    tree of a unit-scale scene with every coordinate scaled by 1e-10 (rounding is monotone, so
    its boxes still hold the scaled triangles): loaded at 2e-10 it would be a valid tree."""
    unit = np.random.default_rng(5).random((300, 3, 3)).astype(np.float32)
    path = tmp_path / "tiny.bvhtree"
    bvhlab.build(unit).save(path)
    data = path.read_bytes()
    start = len(tree_file.MAGIC) + 8
    head_len = struct.unpack_from("<I", data, len(tree_file.MAGIC) + 4)[0]
    header = json.loads(data[start : start + head_len])

    def scaled(scale):
        tiny = (unit.astype(np.float64) * scale).astype(np.float32)
        header["geometry_fingerprint"] = int(bvhlab._core.geometry_fingerprint(tiny, None))
        head = json.dumps(header, sort_keys=True).encode()
        nodes = np.frombuffer(data, bvhlab.bvh.NODE_DTYPE, header["nodes"], start + head_len).copy()
        for field in ("lo", "hi"):
            nodes[field] = (nodes[field].astype(np.float64) * scale).astype(np.float32)
        rest = data[start + head_len + nodes.nbytes : -32]
        body = data[: len(tree_file.MAGIC) + 4] + struct.pack("<I", len(head)) + head + nodes.tobytes() + rest
        path.write_bytes(body + hashlib.sha256(body).digest())
        return tiny

    tiny = scaled(2.4e-10)  # just above 2^-32: loads
    assert len(bvhlab.load_bvh(path, tiny).nodes) > 0
    tiny = scaled(1e-10)
    with pytest.raises(ValueError, match="spans only 1e-10 units"):
        bvhlab.load_bvh(path, tiny)
