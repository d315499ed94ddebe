"""Scenes from OBJ, PLY, STL, glTF and GLB files (bvhlab.library.files, through trimesh): each format
round-trips a known mesh, and each hostile file gets a clear error naming it."""

import json
import os
import struct

import numpy as np
import pytest
import trimesh

from bvhlab import cli
from bvhlab._npz import SceneFileError
from bvhlab.library import load_scene
from bvhlab.library.files import load_mesh_file
from bvhlab.library.gltf_checks import gltf_buffers

FORMATS = ("obj", "ply", "stl", "gltf", "glb")


@pytest.fixture(scope="module")
def source():
    """A known mesh: an icosphere moved off the origin and stretched, so its bounds are not symmetric."""
    mesh = trimesh.creation.icosphere(subdivisions=2)
    mesh.apply_scale((2.0, 1.0, 0.5))
    mesh.apply_translation((3.0, -1.0, 7.0))
    return mesh


@pytest.mark.parametrize("kind", FORMATS)
def test_each_format_round_trips_a_known_mesh(tmp_path, source, kind):
    path = tmp_path / f"sphere.{kind}"
    source.export(path)  # trimesh's own writer: independent of the reader's path through bvhlab
    scene, name = load_scene(str(path))
    assert name == "sphere"
    assert len(scene.triangles) == len(source.faces) == 320
    lo, hi = scene.bounds()
    np.testing.assert_allclose(lo, source.bounds[0], atol=1e-5)
    np.testing.assert_allclose(hi, source.bounds[1], atol=1e-5)
    assert scene.camera is not None  # the default camera frames the mesh


def test_obj_written_by_hand_with_a_quad(tmp_path):
    path = tmp_path / "quad.obj"
    path.write_text("v 0 0 0\nv 2 0 0\nv 2 3 0\nv 0 3 0\nv 0 0 5\nf 1 2 3 4\nf 1 2 5\n")
    scene = load_mesh_file(path)
    assert len(scene.triangles) == 3  # the quad as two triangles, and one triangle
    lo, hi = scene.bounds()
    assert lo.tolist() == [0, 0, 0] and hi.tolist() == [2, 3, 5]


def test_gltf_scene_graph_places_the_meshes(tmp_path, source):
    """Two copies of the mesh under nodes with translations: both are placed in world space."""
    scene = trimesh.Scene()
    scene.add_geometry(source, node_name="a", transform=trimesh.transformations.translation_matrix((10, 0, 0)))
    scene.add_geometry(source, node_name="b", transform=trimesh.transformations.translation_matrix((-10, 0, 0)))
    path = tmp_path / "two.glb"
    scene.export(path)
    loaded = load_mesh_file(path)
    assert len(loaded.triangles) == 2 * len(source.faces)
    lo, hi = loaded.bounds()
    np.testing.assert_allclose(lo[0], source.bounds[0][0] - 10, atol=1e-5)
    np.testing.assert_allclose(hi[0], source.bounds[1][0] + 10, atol=1e-5)


def _binary_stl(count: int, triangles: int) -> bytes:
    return b"\0" * 80 + struct.pack("<I", count) + b"\0" * (50 * triangles)


def _ply_header(vertices: int, faces: int, fmt: str = "binary_little_endian") -> bytes:
    return (
        f"ply\nformat {fmt} 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\n"
        f"property float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
    ).encode()


def _glb_claiming(count: int) -> bytes:
    """A GLB whose one accessor claims `count` vertices in a 36-byte buffer."""
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": 36}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    }
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    data = np.zeros(9, np.float32).tobytes()
    chunks = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(data), b"BIN\0") + data
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


HOSTILE = {
    "truncated.ply": _ply_header(3, 1) + b"\0" * 10,
    "truncated.glb": _glb_claiming(3)[:40],
    "truncated.stl": _binary_stl(2, 1),
    "ply_named.stl": _ply_header(3, 1, "ascii") + b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    "text_named.glb": b"this is not a glb file at all\n",
    "nan.obj": b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
    "inf.obj": b"v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n",
    "huge_coordinate.obj": b"v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n",
    "no_faces.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\n",
    "empty.stl": b"",
    "points.ply": _ply_header(3, 0, "ascii") + b"0 0 0\n1 0 0\n0 1 0\n",
    "billions.ply": _ply_header(4_000_000_000, 4_000_000_000) + b"\0" * 64,
    "billions_ascii.ply": _ply_header(4_000_000_000, 1, "ascii") + b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    "billions.stl": _binary_stl(4_000_000_000, 1),
    "billions.glb": _glb_claiming(4_000_000_000),
    "bad_index.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
}


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_file_gets_a_clear_error_naming_it(tmp_path, name):
    path = tmp_path / name
    path.write_bytes(HOSTILE[name])
    with pytest.raises(SceneFileError) as e:
        load_mesh_file(path)
    assert str(path) in str(e.value)


def test_huge_header_is_refused_before_reading(tmp_path):
    path = tmp_path / "billions.ply"
    path.write_bytes(HOSTILE["billions.ply"])
    with pytest.raises(SceneFileError, match="declares 4000000000 vertex elements"):
        load_mesh_file(path)


def test_folder_with_a_mesh_suffix(tmp_path):
    (tmp_path / "dir.obj").mkdir()
    with pytest.raises(SceneFileError, match="is a folder"):
        load_mesh_file(tmp_path / "dir.obj")


def test_gltf_whose_buffer_is_missing_names_the_gltf_and_the_buffer(tmp_path, source):
    """The probe's case: a .gltf whose buffer file is gone said only "missing.bin" (a bare
    FileNotFoundError of the buffer, as if the .gltf itself were missing)."""
    source.export(tmp_path / "sphere.gltf")  # writes sphere.gltf and its buffer file beside it
    gltf = json.loads((tmp_path / "sphere.gltf").read_text())
    gltf["buffers"][0]["uri"] = "missing.bin"
    (tmp_path / "sphere.gltf").write_text(json.dumps(gltf))
    with pytest.raises(SceneFileError, match=r"sphere\.gltf refers to .*missing\.bin.*, which is missing"):
        load_mesh_file(tmp_path / "sphere.gltf")


@pytest.mark.parametrize("cameras", [False, True])
def test_gltf_buffer_uris_are_percent_decoded(tmp_path, source, cameras):
    """The probe's case: Blender's glTF export of "my model.gltf" writes its buffer's URI as
    "my%20model.bin" (URIs are percent-encoded); trimesh looked for that name as written and the
    file was "missing". Read both where trimesh reads the file and where bvhlab mends it first
    (a camera node). A name whose "%" was written unencoded is still found as written."""
    source.export(tmp_path / "sphere.gltf")
    doc = json.loads((tmp_path / "sphere.gltf").read_text())
    if cameras:
        doc = _camera_nodes(doc)
    current = tmp_path / doc["buffers"][0]["uri"]
    for name, uri in (("my model #1.bin", "my%20model%20%231.bin"), ("a%20b.bin", "a%20b.bin")):
        current = current.rename(tmp_path / name)
        doc["buffers"][0]["uri"] = uri
        path = tmp_path / "my model.gltf"
        path.write_text(json.dumps(doc))
        scene = load_mesh_file(path)
        assert len(scene.triangles) == (2 if cameras else 1) * len(source.faces), uri
        np.testing.assert_allclose(scene.bounds()[0], source.bounds[0], atol=1e-5)
        assert gltf_buffers(path)[0] == current, "the sweep's cache hashes the file the loader read"


@pytest.mark.parametrize("kind", ["buffers", "images"])
def test_a_fifo_a_gltf_refers_to_is_refused_without_hanging(tmp_path, source, kind):
    """A buffer or image file that is a FIFO blocked trimesh's read (the reviews)."""
    source.export(tmp_path / "s.gltf")
    doc = json.loads((tmp_path / "s.gltf").read_text())
    if kind == "images":
        doc["images"] = [{"uri": "texture.png"}]
        (tmp_path / "s.gltf").write_text(json.dumps(doc))
    name = doc[kind][0]["uri"]
    (tmp_path / name).unlink(missing_ok=True)
    os.mkfifo(tmp_path / name)
    with pytest.raises(SceneFileError, match="is not a regular file .*not a file a glTF refers to"):
        load_mesh_file(tmp_path / "s.gltf")


def test_missing_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_mesh_file(tmp_path / "missing.stl")


def test_cli_builds_a_mesh_file_and_refuses_a_hostile_one(tmp_path, source, capsys):
    good = tmp_path / "sphere.ply"
    source.export(good)
    assert cli.main(["build", str(good), "--method", "median"]) == 0
    assert "sphere: 320 triangles" in capsys.readouterr().out
    bad = tmp_path / "nan.obj"
    bad.write_bytes(HOSTILE["nan.obj"])
    assert cli.main(["build", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("bvhlab build: error:") and str(bad) in err[0]


def _glb_with_json(glb: bytes, doc: dict) -> bytes:
    """A GLB with its JSON chunk replaced by `doc` (spaces to a multiple of 4 bytes), its binary
    chunk kept."""
    old = struct.unpack_from("<I", glb, 12)[0]
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    rest = glb[20 + old :]
    chunk = struct.pack("<I4s", len(text), b"JSON") + text
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunk) + len(rest)) + chunk + rest


def _camera_nodes(doc: dict) -> dict:
    """The mesh twice: on a node that also holds a camera (moved 5 in x), and below a camera node
    (moved 3 in z), as a mesh parented to a camera; trimesh alone left out both."""
    doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}]
    doc["nodes"] = [
        {"mesh": 0, "camera": 0, "translation": [5, 0, 0]},
        {"camera": 0, "translation": [0, 0, 3], "children": [2]},
        {"mesh": 0},
    ]
    doc["scenes"] = [{"nodes": [0, 1]}]
    doc["scene"] = 0
    return doc


@pytest.mark.parametrize("kind", ["gltf", "glb"])
def test_meshes_on_and_below_camera_nodes_are_read(tmp_path, source, kind):
    """The probe's case: a mesh on a camera node was dropped silently (2 of 4 triangles loaded),
    one parented to a camera failed with "No path from world->1"."""
    path = tmp_path / f"sphere.{kind}"
    source.export(path)  # a .gltf's buffer is written beside it: found when the file is mended
    if kind == "gltf":
        path.write_text(json.dumps(_camera_nodes(json.loads(path.read_text()))))
    else:
        glb = path.read_bytes()
        doc = json.loads(glb[20 : 20 + struct.unpack_from("<I", glb, 12)[0]])
        path.write_bytes(_glb_with_json(glb, _camera_nodes(doc)))
    scene = load_mesh_file(path)
    assert len(scene.triangles) == 2 * len(source.faces)
    lo, hi = scene.bounds()
    np.testing.assert_allclose(lo, source.bounds[0], atol=1e-5)  # the copy below the camera: z + 3
    np.testing.assert_allclose(hi, source.bounds[1] + (5, 0, 3), atol=1e-5)


def test_morph_targets_shown_with_a_weight_are_refused(tmp_path, source):
    """trimesh reads the base shape: a morph target with weight 1 (the mesh's or the node's) gave
    a shape half the size without a word; at weight 0 the base shape is what is shown."""
    path = tmp_path / "sphere.gltf"
    source.export(path)
    doc = json.loads(path.read_text())
    position = doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
    doc["meshes"][0]["primitives"][0]["targets"] = [{"POSITION": position}]
    for weights, node_weights in (([1.0], None), ([0.0], [0.5])):
        doc["meshes"][0]["weights"] = weights
        doc["nodes"][0].pop("weights", None)
        if node_weights is not None:
            doc["nodes"][0]["weights"] = node_weights
        path.write_text(json.dumps(doc))
        with pytest.raises(SceneFileError, match="morph target weights .* bvhlab does not apply"):
            load_mesh_file(path)
    doc["nodes"][0]["weights"] = [0.0]
    path.write_text(json.dumps(doc))
    assert len(load_mesh_file(path).triangles) == len(source.faces)


def test_a_json_gltf_named_glb_has_its_buffers_hashed(tmp_path, source):
    """A text glTF saved as .glb is read by its contents, but the sweep's cache key followed the
    buffers of GLB files and .gltf names only: its .bin went unhashed, and after the .bin was
    edited a rerun reused the old cells (probe: SAH 23.4 in the table, 31.0 measured)."""
    from bvhlab.sweep.cells import scene_hash

    source.export(tmp_path / "sphere.gltf")
    doc = json.loads((tmp_path / "sphere.gltf").read_text())
    path = tmp_path / "model.glb"
    path.write_text(json.dumps(doc))
    buffers = [tmp_path / b["uri"] for b in doc["buffers"]]
    assert gltf_buffers(path) == buffers
    assert len(load_mesh_file(path).triangles) == len(source.faces)
    buffer = buffers[-1]
    before = scene_hash(str(path))
    data = bytearray(buffer.read_bytes())
    data[-1] ^= 1
    buffer.write_bytes(bytes(data))
    assert scene_hash(str(path)) != before, "an edited buffer changes the scene's key"
