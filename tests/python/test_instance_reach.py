"""The coordinate-range check of a sync's instances (instancing.instance_transforms and
transforms_again) is one vectorised pass, not a call per mesh or per moved instance: 10,000 movers
(each an animated object with a mesh of its own) spent 0.6 s of every frame in it. And it still
names the instance that reaches out of range."""

import numpy as np
import pytest

from bvhlab.blender import instancing
from bvhlab.blender.errors import ExportError
from bvhlab.blender.instancing import Layout, SharedMesh


class _Mesh:
    def __init__(self, lo, hi):
        self.bounds = np.array([lo, hi], np.float64)


def _movers(n: int):
    """n items, each an instance of a mesh of its own (movers), cubes of half size 1 along x."""
    keys = [(f"M{i}", f"M{i}", ()) for i in range(n)]
    layout = Layout(mesh_of={key: i + 1 for i, key in enumerate(keys)}, groups=[(i, b"") for i in range(n)])
    meshes = [
        SharedMesh(_Mesh((-1, -1, -1), (1, 1, 1)), np.zeros((12, 3, 3), np.float32), np.zeros(12, np.int32))
        for _ in range(n)
    ]
    matrices = np.tile(np.eye(4), (n, 1, 1))
    matrices[:, 0, 3] = np.arange(n) * 3.0
    return keys, layout, meshes, matrices


def _counting(monkeypatch) -> list:
    calls = []
    real = instancing._check_reach

    def counted(*args):
        calls.append(len(args[1]))
        return real(*args)

    monkeypatch.setattr(instancing, "_check_reach", counted)
    return calls


def test_the_reach_of_many_meshes_is_checked_in_one_pass(monkeypatch):
    keys, layout, meshes, matrices = _movers(5000)
    calls = _counting(monkeypatch)
    mesh_of, transforms = instancing.instance_transforms(layout, matrices, meshes)
    assert len(calls) <= 1, f"{len(calls)} calls for 5,000 meshes"
    assert np.array_equal(mesh_of, np.arange(1, 5001)) and np.allclose(transforms[:, 0, 3], np.arange(5000) * 3.0)
    calls.clear()
    moved = matrices.copy()
    moved[:, 1, 3] += 1.0
    out = instancing.transforms_again(transforms, layout, moved, meshes, np.arange(5000))
    assert len(calls) <= 1, f"{len(calls)} calls for 5,000 moved instances"
    assert np.allclose(out[:, 1, 3], 1.0)


@pytest.mark.parametrize("chunk", [1 << 16, 7])  # one pass, or many (each its own bounds and names)
@pytest.mark.parametrize("row", [0, 1234, 4999])
def test_an_instance_out_of_range_is_named(row, chunk, monkeypatch):
    monkeypatch.setattr(instancing, "_REACH_CHUNK", chunk)
    keys, layout, meshes, matrices = _movers(5000)
    _, transforms = instancing.instance_transforms(layout, matrices, meshes)
    far = matrices.copy()
    far[row, 2, 3] = 1e13  # beyond ±2^40
    with pytest.raises(ExportError, match=f"'M{row}'"):
        instancing.instance_transforms(layout, far, meshes)
    with pytest.raises(ExportError, match=f"'M{row}'"):
        instancing.transforms_again(transforms, layout, far, meshes, np.array([row, (row + 1) % 5000]))
    meshes[row] = SharedMesh(_Mesh((-1, -1, -1e13), (1, 1, 1)), meshes[row].triangles, meshes[row].tri_material)
    with pytest.raises(ExportError, match=f"'M{row}'"):  # each instance checked against its own mesh's box
        instancing.instance_transforms(layout, matrices, meshes)
