"""A mesh tree of an InstancedBvh changed through `meshes[k]` (refit, update): a change that moves an
instance outside the coordinate range is refused and undone, and the InstancedBvh keeps answering
(it kept the change, and every later read raised, `meshes` too: a helper's audit)."""

import gc

import numpy as np
import pytest

import bvhlab

TRIANGLE = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], np.float32)
MESH = np.concatenate([TRIANGLE, TRIANGLE + 2])


def _scene(scale: float = 1e6) -> bvhlab.Scene:
    """Mesh 0 as modelled; mesh 1 placed once where modelled and once scaled by `scale` at x = 5."""
    transforms = np.zeros((3, 3, 4), np.float32)
    transforms[:, :, :3] = np.eye(3)
    transforms[2, :, :3] *= scale
    transforms[2, 0, 3] = 5
    return bvhlab.Scene(
        triangles=MESH, meshes=[MESH], instance_mesh=np.array([0, 1, 1]), instance_transforms=transforms
    )


def _rays(n: int = 500):
    rng = np.random.default_rng(3)
    origins = rng.uniform(-3, 6, (n, 3)).astype(np.float32)
    origins[:, 2] = 5
    dirs = np.tile(np.float32([0, 0, -1]), (n, 1))
    return origins, dirs


@pytest.mark.parametrize("how", ["refit", "update", "update_rebuild"])
def test_a_change_that_moves_an_instance_out_of_range_is_refused_and_undone(how):
    tree = bvhlab.build(_scene())
    origins, dirs = _rays()
    before = tree.intersect(origins, dirs)
    stats = tree.stats
    mesh = tree.meshes[1]
    revision = mesh.revision
    far = MESH + np.float32(1e7)  # within range in the mesh's space, ×1e6 past 2^40 in the world
    change = {
        "refit": lambda: mesh.refit(far),
        "update": lambda: mesh.update(far, policy="refit"),
        "update_rebuild": lambda: mesh.update(far, policy="rebuild"),
    }[how]
    with pytest.raises(ValueError, match=r"change refused, the tree kept as it was.*instance 2.*coordinate range"):
        change()
    # the tree as it was, as a new revision (a cache of the undone one is never taken for it)
    assert mesh.revision == revision + 2
    np.testing.assert_array_equal(mesh.refs, tree.meshes[1].refs)
    assert float(mesh.nodes["hi"].max()) == pytest.approx(3.0)
    after = tree.intersect(origins, dirs)
    for key in ("t", "prim", "instance"):
        np.testing.assert_array_equal(after[key], before[key])
    timeless = lambda s: {k: v for k, v in s.items() if not k.endswith("_ms")}  # noqa: E731
    assert timeless(tree.stats) == timeless(stats)
    # and a change within range is taken and followed
    near = MESH + np.float32([0, 0, 1])
    mesh.refit(near)
    moved = bvhlab.build(
        bvhlab.Scene(
            triangles=MESH, meshes=[near], instance_mesh=tree.instances[0], instance_transforms=tree.instances[1]
        )
    )
    np.testing.assert_array_equal(tree.intersect(origins, dirs)["t"], moved.intersect(origins, dirs)["t"])


def test_every_instanced_tree_placing_the_mesh_is_asked():
    """Two InstancedBvhs over the same mesh trees: one places it by 1 (the change fits), the other
    by 1e6 (it does not): refused for both, and neither raises afterwards."""
    small = bvhlab.build(_scene(scale=1.0))
    meshes = list(small.meshes)
    mesh_of, transforms = _scene().instances()
    large = bvhlab.InstancedBvh(meshes, mesh_of, transforms, small.config)
    with pytest.raises(ValueError, match="instance 2"):
        meshes[1].refit(MESH + np.float32(1e7))
    origins, dirs = _rays(50)
    for placed in (small, large):
        assert placed.stats["instances"] == 3
        assert np.isfinite(placed.intersect(origins, dirs)["t"]).any()
    del large, placed  # no longer places it: the same change is now the small tree's alone, and fits
    gc.collect()
    meshes[1].refit(MESH + np.float32(1e7))
    assert small.world_boxes()[1][2, 0] == pytest.approx(1e7 + 8, rel=1e-5)


def test_a_snapshot_does_not_refuse_changes():
    """A snapshot keeps the TLAS it was taken with; it places nothing new, so it asks nothing."""
    tree = bvhlab.build(_scene(scale=1.0))
    view = tree.snapshot()
    tree.meshes[1].refit(MESH + np.float32(1e7))
    assert view.world_boxes()[1][2, 0] == pytest.approx(8.0, rel=1e-5)
    assert tree.world_boxes()[1][2, 0] == pytest.approx(1e7 + 8, rel=1e-5)
