"""Scene.mesh_tri_material (issue 34): the materials of meshes 1.., kept by flattened(), files and
the two-level renderer, and refused when they do not fit."""

import numpy as np
import pytest

import bvhlab


def _tetrahedron(offset=0.0) -> np.ndarray:
    p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32) + offset
    return np.ascontiguousarray(p[[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]])


def _scene(**extra) -> bvhlab.Scene:
    red, green = bvhlab.Material((0.9, 0.1, 0.1)), bvhlab.Material((0.1, 0.9, 0.1))
    return bvhlab.Scene(
        triangles=_tetrahedron(-3.0),
        materials=[bvhlab.Material(), red, green],
        meshes=[_tetrahedron()],
        mesh_tri_material=[np.array([1, 2, 1, 2])],
        instance_mesh=np.array([0, 1, 1]),
        instance_transforms=np.array(
            [np.eye(4)[:3], np.eye(4)[:3], [[2, 0, 0, 2], [0, 1, 0, 0], [0, 0, -1, 0]]], np.float32
        ),
        **extra,
    )


def test_flattened_keeps_each_meshs_materials():
    flat = _scene().flattened()
    assert flat.tri_material.tolist() == [0, 0, 0, 0] + [1, 2, 1, 2] * 2


def test_file_round_trip(tmp_path):
    loaded = bvhlab.Scene.load(_scene().save(tmp_path / "s.npz"))
    assert [m.tolist() for m in loaded.mesh_tri_material] == [[1, 2, 1, 2]]
    assert np.array_equal(loaded.flattened().tri_material, _scene().flattened().tri_material)


def test_without_it_meshes_use_material_0():
    scene = _scene()
    scene.mesh_tri_material = []
    assert scene.mesh_triangle_material(1).tolist() == [0, 0, 0, 0]


@pytest.mark.parametrize(
    "value, message",
    [
        ([np.array([1, 2, 1])], "must be 4 integers"),
        ([np.array([1, 2, 1, 7])], "does not exist"),
        ([np.array([1, 2, 1, 2]), np.zeros(4, np.int32)], "2 arrays for 1 meshes"),
    ],
)
def test_bad_materials_are_named(value, message):
    scene = _scene()
    scene.mesh_tri_material = value
    with pytest.raises(ValueError, match=message):
        scene.flattened()


def test_two_level_render_shows_the_mesh_materials():
    scene = _scene()
    image, _ = bvhlab.render(scene, bvhlab.build(scene), 48, 32, backend="cpu")
    flat = scene.flattened()
    reference, _ = bvhlab.render(flat, bvhlab.build(flat), 48, 32, backend="cpu", camera=scene.camera)
    red = (image[..., 0] > 2 * image[..., 1]) & (image[..., 0] > 0.1)
    assert red.any(), "mesh 1's red triangles are not in the picture"
    assert (np.abs(image - reference).max(-1) > 1e-3).mean() <= 0.05
