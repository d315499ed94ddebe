"""bvhlab.Scene: defaults that frame the geometry, and .npz round trips without pickle."""
import numpy as np
import pytest

import bvhlab
from bvhlab.library import procedural


def test_defaults_frame_the_geometry(knot_mesh):
    scene = bvhlab.Scene(triangles=knot_mesh)
    cam = scene.camera
    assert cam.fov_y == 45.0
    lo, hi = scene.bounds()
    center = (lo + hi) / 2
    np.testing.assert_allclose(cam.look_at, center, rtol=1e-6)
    pos = np.array(cam.position)
    assert pos[2] > center[2] and pos[1] < center[1], "from the front-upper diagonal (Z up, front = -Y)"
    # every corner of the bounds lies inside the vertical field of view
    fwd = (center - pos) / np.linalg.norm(center - pos)
    for corner in np.array(np.meshgrid(*zip(lo, hi))).T.reshape(-1, 3):
        v = corner - pos
        angle = np.degrees(np.arccos(v @ fwd / np.linalg.norm(v)))
        assert angle < 22.5
    assert scene.light is not None and scene.materials == [bvhlab.Material()]
    assert np.all(scene.tri_material == 0)


def test_save_load_round_trip(tmp_path, small_scene):
    tris, spheres = small_scene
    scene = bvhlab.Scene(
        triangles=tris, spheres=spheres,
        materials=[bvhlab.Material((1, 0, 0)), bvhlab.Material((0.9, 0.9, 0.9), reflective=0.8),
                   bvhlab.Material(transparent=0.9, ior=1.33)],
        tri_material=np.arange(len(tris)) % 3, sphere_material=np.full(len(spheres), 2),
        camera=bvhlab.Camera((0, -5, 2), (0.5, 0.5, 0.5), fov_y=60),
        light=bvhlab.Light((3, -3, 6), (1, 0.9, 0.8), 2.0), sky=(0.1, 0.2, 0.3))
    path = tmp_path / "scene.npz"
    scene.save(path)
    with np.load(path, allow_pickle=False) as f:  # plain arrays only
        assert all(f[k].dtype != object for k in f.files)
    back = bvhlab.Scene.load(path)
    np.testing.assert_array_equal(back.triangles, tris)
    np.testing.assert_array_equal(back.spheres, spheres)
    np.testing.assert_array_equal(back.tri_material, scene.tri_material)
    assert back.materials == scene.materials
    assert back.camera == scene.camera and back.light == scene.light
    assert back.sky == pytest.approx(scene.sky)
    a, b = bvhlab.build(scene), bvhlab.build(back)
    assert a.nodes.tobytes() == b.nodes.tobytes()


def test_load_rejects_other_files(tmp_path):
    with pytest.raises(FileNotFoundError):
        bvhlab.Scene.load(tmp_path / "missing.npz")
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(ValueError, match="not a bvhlab scene"):
        bvhlab.Scene.load(tmp_path / "other.npz")


def test_empty_scene_has_no_camera_until_given_one():
    scene = bvhlab.Scene()
    assert scene.primitive_count == 0 and scene.camera is None
    scene = bvhlab.Scene(spheres=procedural.random_spheres(3))
    assert scene.camera is not None
