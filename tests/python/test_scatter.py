"""library.scatter.knot_field (`gen:knot_field`): a deterministic instanced scene whose two-level
tree hits what one flat tree over its triangles moved into the world hits."""

import numpy as np
import pytest

import bvhlab
from bvhlab.library import load_scene
from bvhlab.library.scatter import knot_field


def test_a_small_field_hits_what_its_flattened_triangles_hit():
    scene = knot_field(count=40, knot_triangles=600, seed=3)
    mesh_of, transforms = scene.instances()
    assert scene.is_instanced and len(mesh_of) == 41 and set(mesh_of[1:].tolist()) == {1, 2}
    assert np.array_equal(transforms[0], np.eye(3, 4, dtype=np.float32))
    flat = scene.flattened()
    assert len(flat.triangles) == sum(len(scene.mesh_triangles(int(k))) for k in mesh_of)
    rng = np.random.default_rng(0)
    lo, hi = scene.bounds()
    origins = (lo + (hi - lo) * rng.random((2000, 3)) + np.array([0, 0, 1.0])).astype(np.float32)
    targets = lo + (hi - lo) * rng.random((2000, 3))
    dirs = (targets - origins).astype(np.float32)
    two = bvhlab.build(scene).intersect(origins, dirs)
    one = bvhlab.build(flat).intersect(origins, dirs)
    hit = one["prim"] >= 0
    assert hit.mean() > 0.3
    assert np.array_equal(two["prim"] >= 0, hit)
    np.testing.assert_allclose(two["t"][hit], one["t"][hit], rtol=1e-4)


def test_the_field_is_deterministic_and_checks_its_count():
    a, b = knot_field(count=5, knot_triangles=200), knot_field(count=5, knot_triangles=200)
    assert np.array_equal(a.instances()[1], b.instances()[1]) and np.array_equal(a.meshes[0], b.meshes[0])
    with pytest.raises(ValueError, match="count must be >= 1"):
        knot_field(count=0)


def test_the_named_scene_is_two_thousand_instances_of_three_meshes():
    scene, name = load_scene("gen:knot_field")
    assert name == "knot_field" and scene.mesh_count == 3 and len(scene.instances()[0]) == 2001
