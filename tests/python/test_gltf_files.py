"""glTF and GLB through trimesh after bvhlab's checks (bvhlab.library.gltf_checks), on files written
here by hand, each against figures computed here: what trimesh reads wrong refused by name (Draco,
sparse accessors, normalized quantization, fans, GPU instancing, skins, morph weights, data that is
not in the file), what it reads right left alone, and buffers found where their URIs say (split
from test_mesh_readers.py)."""

import json
import struct

import numpy as np
import pytest
from test_mesh_readers import load

from bvhlab._npz import SceneFileError


def gltf(**changes) -> str:
    """A glTF of one triangle (positions in a data: URI), with top-level fields changed."""
    data = np.array([0, 0, 0, 1, 0, 0, 0, 1, 0], np.float32).tobytes()
    import base64

    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [
            {"byteLength": 36, "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}
        ],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}
        ],
    }
    for key, change in changes.items():
        change(doc) if callable(change) else doc.__setitem__(key, change)
    return json.dumps(doc)


def _set(path: list, value):
    def change(doc):
        target = doc
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value

    return change


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"extensionsRequired": ["KHR_draco_mesh_compression"]}, "requires the glTF extension KHR_draco"),
        ({"extensionsRequired": ["EXT_meshopt_compression"]}, "requires the glTF extension EXT_meshopt"),
        ({"n": _set(["nodes", 0, "extensions"], {"EXT_mesh_gpu_instancing": {"attributes": {}}})}, "gpu_instancing"),
        ({"s": _set(["accessors", 0, "sparse"], {"count": 1})}, "sparse accessors are not read"),
        ({"q": _set(["accessors", 0, "normalized"], True)}, "normalized positions"),
        ({"f": _set(["meshes", 0, "primitives", 0, "mode"], 6)}, "triangle fans"),
        # a skinned mesh was placed by its node (skinning ignores it): 100 units off Blender's import
        ({"k": _set(["nodes", 0, "skin"], 0)}, "skinned mesh"),
        # a helper's audit: overlapping vertices, an offset from the buffer's end, all but the last
        ({"b": _set(["bufferViews", 0, "byteStride"], 4)}, "byteStride 4 is not 12 to 252 bytes"),
        ({"o": _set(["bufferViews", 0, "byteOffset"], -60)}, "byteOffset is -60, not a count of 0 or more"),
        ({"c": _set(["accessors", 0, "count"], -1)}, "accessor 0's count is -1"),
        # zeros: 30M of them took 4.7 GB; degenerate triangles at the origin where it is POSITION
        (
            {"z": lambda d: d["accessors"].append({"componentType": 5126, "count": 30_000_000, "type": "VEC3"})},
            "accessor 1 declares 30000000 elements of zeros",
        ),
        ({"p": lambda d: d["accessors"][0].pop("bufferView")}, "positions have no buffer view"),
        ({"v": _set(["accessors", 0, "type"], "VEC2")}, "positions are 'VEC2', not VEC3"),
        (
            {
                "i": lambda d: (
                    d["accessors"].append({"bufferView": 1, "componentType": 5121, "count": 8, "type": "SCALAR"}),
                    d["bufferViews"].append({"buffer": 0, "byteLength": 8}),
                    d["meshes"][0]["primitives"][0].__setitem__("indices", 1),
                )
            },
            "has 8 indices of triangles, not a multiple of 3",
        ),
    ],
)
def test_gltf_that_trimesh_would_read_wrong_is_refused(tmp_path, changes, message):
    with pytest.raises(SceneFileError, match=message):
        load(tmp_path, "model.gltf", gltf(**changes))


def test_gltf_checks_leave_good_files_alone(tmp_path):
    t = load(tmp_path, "model.gltf", gltf(extensionsRequired=["KHR_materials_emissive_strength"]))
    np.testing.assert_array_equal(t[0], [(0, 0, 0), (1, 0, 0), (0, 1, 0)])


def test_gltf_after_a_byte_order_mark_is_read(tmp_path):
    """trimesh's JSON parse failed on the BOM and it looked for a "model.gltf" it was not given:
    "refers to model.gltf, which is missing" (a helper's probe)."""
    t = load(tmp_path, "bom.gltf", b"\xef\xbb\xbf" + gltf().encode())
    np.testing.assert_array_equal(t[0], [(0, 0, 0), (1, 0, 0), (0, 1, 0)])


def _draco_used(doc):
    """The Draco extension on the primitive, used but not required, its accessor without data."""
    doc["extensionsUsed"] = ["KHR_draco_mesh_compression"]
    doc["meshes"][0]["primitives"][0]["extensions"] = {
        "KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}
    }
    del doc["accessors"][0]["bufferView"]


@pytest.mark.parametrize(
    "changes, message",
    [
        # its accessor all zeros: 1 triangle of zeros, exit 0 (a helper's probe)
        ({"d": _draco_used}, "compressed by KHR_draco_mesh_compression without uncompressed data"),
        # the data: URI holds 36 bytes; a buffer declared longer, its view past the 36 (trimesh:
        # "AssertionError")
        (
            {"b": _set(["buffers", 0, "byteLength"], 48), "v": _set(["bufferViews", 0, "byteLength"], 48)},
            "runs past the 36 bytes the file holds for buffer 0",
        ),
    ],
)
def test_gltf_whose_data_is_not_there_is_refused(tmp_path, changes, message):
    with pytest.raises(SceneFileError, match=message):
        load(tmp_path, "model.gltf", gltf(**changes))


def test_gltf_buffer_files_and_glb_chunks_shorter_than_declared_are_refused(tmp_path):
    """A .bin 8 bytes short and a GLB without its binary chunk (trimesh: "list index out of range")."""
    data = np.array([0, 0, 0, 1, 0, 0, 0, 1, 0], np.float32).tobytes()
    (tmp_path / "short.bin").write_bytes(data[:28])
    with pytest.raises(SceneFileError, match="past the 28 bytes the file holds for buffer 0 .declared 36"):
        load(tmp_path, "model.gltf", gltf(buffers=[{"byteLength": 36, "uri": "short.bin"}]))
    text = gltf(buffers=[{"byteLength": 36}]).encode()
    text += b" " * (-len(text) % 4)
    chunk = struct.pack("<I4s", len(text), b"JSON") + text
    glb = struct.pack("<4sII", b"glTF", 2, 12 + len(chunk)) + chunk
    with pytest.raises(SceneFileError, match="past the 0 bytes the file holds for buffer 0"):
        load(tmp_path, "model.glb", glb)
    whole = glb[:8] + struct.pack("<I", 12 + len(chunk) + 8 + 36) + glb[12:] + struct.pack("<I4s", 36, b"BIN\0") + data
    np.testing.assert_array_equal(load(tmp_path, "whole.glb", whole)[0], [(0, 0, 0), (1, 0, 0), (0, 1, 0)])


@pytest.mark.parametrize("text", ["", '{"asset": ', "not json"])
def test_gltf_that_is_not_json_says_so(tmp_path, text):
    with pytest.raises(SceneFileError, match="is not glTF: its JSON cannot be read"):
        load(tmp_path, "model.gltf", text)


@pytest.mark.parametrize(
    "changes",
    [
        {"extensionsRequired": 5},
        {"extensionsRequired": "KHR_materials_x"},
        {"a": _set(["meshes", 0, "primitives", 0, "attributes"], [1])},
    ],
)
def test_gltf_with_values_of_the_wrong_type_is_not_gltf(tmp_path, changes):
    with pytest.raises(SceneFileError):  # TypeError and AttributeError escaped
        load(tmp_path, "model.gltf", gltf(**changes))


def test_gltf_buffers_are_read_where_their_uris_say(tmp_path):
    """A probe's case: a URI that leads out of the glTF's folder ("../shared/buf.bin", an absolute
    path, a URL) was read from a file of the same name beside the glTF, another mesh, silently."""
    real = np.array([0, 0, 0, 1, 0, 0, 0, 1, 0], np.float32)
    (tmp_path / "shared").mkdir()
    (tmp_path / "shared" / "buf.bin").write_bytes(real.tobytes())
    (tmp_path / "A").mkdir()
    (tmp_path / "A" / "buf.bin").write_bytes((real + 50).tobytes())  # same name, other triangle

    def with_uri(uri: str) -> str:
        return gltf(buffers=[{"byteLength": 36, "uri": uri}])

    for uri in ("../shared/buf.bin", str(tmp_path / "shared" / "buf.bin"), "../shared/b%75f.bin"):
        t = load(tmp_path / "A", "model.gltf", with_uri(uri))
        np.testing.assert_array_equal(t[0], real.reshape(3, 3), err_msg=uri)
    np.testing.assert_array_equal(load(tmp_path / "A", "model.gltf", with_uri("buf.bin"))[0], (real + 50).reshape(3, 3))
    for uri in ("http://example.com/buf.bin", "file:///tmp/buf.bin"):
        with pytest.raises(SceneFileError, match="a URL: only files are read"):
            load(tmp_path / "A", "model.gltf", with_uri(uri))
    with pytest.raises(SceneFileError, match="missing"):
        load(tmp_path / "A", "model.gltf", with_uri("../elsewhere/buf.bin"))
    # a data: URI that is not base64: its start, not its whole payload (a helper's audit)
    with pytest.raises(SceneFileError, match=r"'data:application/octet-stream,0{30}\.\.\. \(100030 characters\)'"):
        load(tmp_path / "A", "model.gltf", with_uri("data:application/octet-stream," + "0" * 100_000))


@pytest.mark.parametrize(
    "changes, message",
    [
        (
            {"v": _set(["bufferViews", 0, "byteLength"], 48)},
            r"buffer view 0 \(0 \+ 48 bytes\) runs past the end of buffer 0",
        ),
        (
            {"a": _set(["accessors", 0, "count"], 4)},
            r"accessor 0 \(4 elements, 48 bytes\) runs past the end of buffer view 0",
        ),
        ({"n": _set(["nodes", 0, "mesh"], 5)}, r"node 0 refers to mesh 5, which the file does not have \(1\)"),
        ({"p": _set(["meshes", 0, "primitives", 0, "attributes", "POSITION"], 3)}, "POSITION refers to accessor 3"),
        ({"i": _set(["meshes", 0, "primitives", 0, "indices"], 0)}, "indices have component type 5126"),
    ],
)
def test_gltf_references_that_lead_nowhere_are_named(tmp_path, changes, message):
    """A probe's cases: trimesh refused them as "AssertionError", or read "0 faces"."""
    with pytest.raises(SceneFileError, match=message):
        load(tmp_path, "model.gltf", gltf(**changes))


def test_gltf_uri_query_fragment_and_network_paths(tmp_path):
    """The review's cases: "buf.bin?v=2" names buf.bin (RFC 3986: the query is no part of the
    path), a "#" an exporter left unencoded still finds its file, and "//host/share/buf.bin" (a
    network path, a UNC share on Windows) is a URL, not read."""
    real = np.array([0, 0, 0, 1, 0, 0, 0, 1, 0], np.float32)
    (tmp_path / "buf.bin").write_bytes(real.tobytes())
    (tmp_path / "a#b.bin").write_bytes((real + 5).tobytes())

    def with_uri(uri: str) -> str:
        return gltf(buffers=[{"byteLength": 36, "uri": uri}])

    np.testing.assert_array_equal(load(tmp_path, "m.gltf", with_uri("buf.bin?v=2"))[0], real.reshape(3, 3))
    np.testing.assert_array_equal(load(tmp_path, "m.gltf", with_uri("buf.bin#x"))[0], real.reshape(3, 3))
    np.testing.assert_array_equal(load(tmp_path, "m.gltf", with_uri("a#b.bin"))[0], (real + 5).reshape(3, 3))
    for uri in ("//host/share/buf.bin", "\\\\host\\share\\buf.bin"):
        with pytest.raises(SceneFileError, match="a URL: only files are read"):
            load(tmp_path, "m.gltf", with_uri(uri))
