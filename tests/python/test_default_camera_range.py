"""Geometry that reaches near ±MAX_COORDINATE is valid (probe): the Scene is made without a camera
where the one framing it would stand outside the range, the tree builds and takes rays, and a
render without a camera says what to give."""

import numpy as np
import pytest

import bvhlab
from bvhlab.scene import MAX_COORDINATE


def _wide_triangle() -> np.ndarray:
    r = np.float32(0.9 * MAX_COORDINATE)
    return np.array([[[-r, -r, 0], [r, -r, 0], [0, r, 0]]], np.float32)


def test_a_flat_scene_near_the_range_limit_is_made_and_takes_rays():
    tris = _wide_triangle()
    scene = bvhlab.Scene(triangles=tris)  # the default camera would stand at ~3e12: none is made
    assert scene.camera is None
    bvh = bvhlab.build(scene)
    hits = bvh.intersect(np.array([[0, 0, 1e6]], np.float32), np.array([[0, 0, -1]], np.float32))
    assert hits["prim"][0] == 0 and hits["t"][0] == np.float32(1e6)


def test_an_instance_moved_near_the_range_limit_is_made_and_takes_rays():
    tris = np.array([[[-1, -1, 0], [1, -1, 0], [0, 1, 0]]], np.float32)
    t = np.repeat(np.eye(3, 4, dtype=np.float32)[None], 2, 0)
    t[1, :, :3] *= np.float32(0.9 * MAX_COORDINATE)
    scene = bvhlab.Scene(triangles=tris, instance_mesh=np.zeros(2, np.int32), instance_transforms=t)
    tree = bvhlab.build(scene)
    hits = tree.intersect(np.array([[0, 0, 5]], np.float32), np.array([[0, 0, -1]], np.float32))
    assert hits["t"][0] == 5 and hits["prim"][0] == 0


def test_a_render_without_a_camera_asks_for_one_and_renders_with_one():
    scene = bvhlab.Scene(triangles=_wide_triangle())
    bvh = bvhlab.build(scene)
    with pytest.raises(ValueError, match="default camera.*give one: camera=bvhlab.Camera"):
        bvhlab.render(scene, bvh, 4, 3, backend="cpu")
    camera = bvhlab.Camera((0.0, -1e11, 1e11), (0.0, 0.0, 0.0))
    image, _ = bvhlab.render(scene, bvh, 4, 3, backend="cpu", camera=camera)
    assert np.isfinite(image).all()


def test_a_scene_within_reach_keeps_its_default_camera():
    tris = _wide_triangle() * np.float32(1e-3)
    assert bvhlab.Scene(triangles=tris).camera is not None
