"""A glTF's node hierarchy (library/gltf_nodes.py): deep ones flattened before trimesh reads them,
with the triangles trimesh itself gives; cycles, nodes with two parents and nodes with a matrix and
TRS refused; JSON that Python's parser cannot take named as the file's (a helper's audit)."""

import json
import subprocess
import sys

import numpy as np
import pytest
from test_gltf_files import gltf
from test_mesh_readers import load

from bvhlab._npz import SceneFileError
from bvhlab.library import gltf_nodes


def _random_hierarchy(rng, count: int) -> list[dict]:
    """`count` nodes, each a child of an earlier one (node 0 the root), placed by TRS or a matrix,
    a mesh on about half of them: deeper than FLAT_DEPTH."""
    nodes: list[dict] = [{} for _ in range(count)]
    for n in range(1, count):
        parent = n - 1 if n < 12 else int(rng.integers(0, n))  # a chain of 12, then branches
        nodes[parent].setdefault("children", []).append(n)
    for node in nodes:
        if rng.random() < 0.5:
            node["mesh"] = 0
        if rng.random() < 0.3:
            m = np.eye(4)
            m[:3, :3] = rng.normal(size=(3, 3))
            m[:3, 3] = rng.normal(size=3)
            node["matrix"] = [float(x) for x in m.T.reshape(-1)]
        else:
            node["translation"] = rng.normal(size=3).tolist()
            node["rotation"] = (rng.normal(size=4) * 3).tolist()  # unnormalised: trimesh normalises
            node["scale"] = rng.uniform(0.5, 2, 3).tolist()
    return nodes


def test_a_deep_hierarchy_is_flattened_to_the_triangles_trimesh_composes(tmp_path, monkeypatch):
    rng = np.random.default_rng(7)
    text = gltf(nodes=_random_hierarchy(rng, 40))
    flattened = load(tmp_path, "deep.gltf", text)
    monkeypatch.setattr(gltf_nodes, "FLAT_DEPTH", 10**9)  # trimesh composes the paths itself
    reference = load(tmp_path, "as_is.gltf", text)
    assert len(flattened) == len(reference) > 15
    # in trimesh's order too: a primitive's index is the same either way (the review)
    np.testing.assert_allclose(flattened, reference, rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize(
    "rotation, roots",
    [((1e-9, 0, 0, 0), [0]), ((2e-8, 0, 0, 0), [0]), ((0, 0, 0, 0), [0]), ((0, 0, 0.3, 1), [0, 0])],
)
def test_flattening_follows_trimesh_on_its_edge_cases(tmp_path, monkeypatch, rotation, roots):
    """A quaternion of squared length below 4 ε is none for trimesh (1e-9 was a turn of 180°
    flattened); a root listed twice is placed once (its triangles came twice: the review)."""
    nodes = [{"children": [n + 1], "rotation": list(rotation)} for n in range(12)] + [{"mesh": 0}]
    nodes[12]["children"] = [13]
    nodes.append({"mesh": 0, "translation": [0, 0, 1]})
    text = gltf(nodes=nodes, scenes=[{"nodes": roots}])
    flattened = load(tmp_path, "deep.gltf", text)
    monkeypatch.setattr(gltf_nodes, "FLAT_DEPTH", 10**9)
    reference = load(tmp_path, "as_is.gltf", text)
    np.testing.assert_allclose(flattened, reference, rtol=1e-6, atol=1e-6)


def test_a_chain_of_thousands_of_nodes_is_read_at_once(tmp_path):
    """A 5,000-node chain: trimesh's composition of it ran for hours (1,000 nodes: 54 s, then
    Python's recursion limit). In a child process, so that a return of it fails, not hangs."""
    nodes = [{"children": [n + 1], "translation": [0.001, 0, 0]} for n in range(5000)] + [{"mesh": 0}]
    path = tmp_path / "chain.gltf"
    path.write_text(gltf(nodes=nodes))
    code = (
        "import sys\nfrom bvhlab.library.files import load_mesh_file\n"
        "print(load_mesh_file(sys.argv[1]).triangles[0].tolist())\n"
    )
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    triangle = np.array(json.loads(out.stdout))
    np.testing.assert_allclose(triangle, [[5, 0, 0], [6, 0, 0], [5, 1, 0]], atol=1e-9 * 5000)


@pytest.mark.parametrize(
    "nodes, message",
    [
        ([{"children": [1]}, {"children": [0], "mesh": 0}], "node 0 is its own ancestor"),
        ([{"children": [0], "mesh": 0}], "node 0 is its own ancestor"),
        ([{"children": [2]}, {"children": [2]}, {"mesh": 0}], "node 2 is a child of nodes 0 and 1"),
        (
            [{"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1], "scale": [2, 2, 2]}],
            "both a matrix",
        ),
        ([{"children": [7], "mesh": 0}], r"node 0's children \[7\] are not nodes of the file"),
    ],
)
def test_nodes_that_are_not_a_forest_are_refused(tmp_path, nodes, message):
    """A node with two parents was placed once, under the last; a matrix and TRS were both applied;
    a cycle read as "Iteration limit exceeded!"."""
    with pytest.raises(SceneFileError, match=message):
        load(tmp_path, "model.gltf", gltf(nodes=nodes, scenes=[{"nodes": [0]}]))


@pytest.mark.parametrize(
    "scenes, message",
    [
        ([{"nodes": [0, 5]}], "scene 0 lists node 5 and its ancestor 0"),  # placed once by trimesh
        ([{"nodes": 5}], r"scene 0's nodes 5 are not nodes of the file"),  # a TypeError, deep only
    ],
)
def test_deep_scenes_that_are_not_lists_of_roots_are_refused(tmp_path, scenes, message):
    nodes = [{"children": [n + 1]} for n in range(12)] + [{"mesh": 0}]
    with pytest.raises(SceneFileError, match=message):
        load(tmp_path, "model.gltf", gltf(nodes=nodes, scenes=scenes))


@pytest.mark.parametrize("text", ["[" * 100_000, '{"asset": {"version": "2.0"}, "n": ' + "7" * 5000 + "}"])
def test_json_python_cannot_parse_is_named_as_the_files(tmp_path, text):
    """RecursionError and "Exceeds the limit (4300 digits)" escaped as themselves, naming no file."""
    with pytest.raises(SceneFileError, match=r"model.gltf is not glTF: its JSON cannot be read"):
        load(tmp_path, "model.gltf", text)
