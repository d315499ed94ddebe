"""Instance and material indices that int32 cannot hold, and scenes with no instances (probe): an
index is refused by name, never wrapped to another mesh; zero instances is an empty world."""

import numpy as np
import pytest

import bvhlab
from bvhlab.library import procedural


def _eye(n: int) -> np.ndarray:
    return np.ascontiguousarray(np.repeat(np.eye(3, 4, dtype=np.float32)[None], n, 0))


@pytest.mark.parametrize("index", [2**32, 2**32 + 1, -(2**32), 2**31])
def test_a_mesh_index_beyond_int32_is_refused_not_wrapped(index):
    # 2^32 as int32 is 0, a mesh that exists: the instance would silently place mesh 0
    tris = procedural.random_triangles(20, seed=1)
    mesh = np.array([0, index], np.int64)
    with pytest.raises(ValueError, match=f"instance 1 refers to mesh {index}"):
        bvhlab.Scene(triangles=tris, instance_mesh=mesh, instance_transforms=_eye(2))


@pytest.mark.parametrize("index", [2**32, -1, 1])
def test_place_refuses_a_mesh_index_the_tree_lacks(index):
    tris = procedural.random_triangles(20, seed=1)
    tree = bvhlab.build(bvhlab.Scene(triangles=tris, instance_mesh=np.zeros(2, np.int32), instance_transforms=_eye(2)))
    before = tree.intersect(*procedural.random_rays(tris, 50, seed=2))["t"]
    with pytest.raises(ValueError, match=f"instance 1 refers to mesh {index}, but the tree has 1 mesh"):
        tree.place(np.array([0, index], np.int64), _eye(2))
    np.testing.assert_array_equal(tree.intersect(*procedural.random_rays(tris, 50, seed=2))["t"], before)


def test_place_keeps_the_checked_indices():
    tris = procedural.random_triangles(20, seed=1)
    tree = bvhlab.build(bvhlab.Scene(triangles=tris, instance_mesh=np.zeros(2, np.int32), instance_transforms=_eye(2)))
    tree.place([0, 0, 0], _eye(3))  # a list is fine; `instances` gives the array it became
    mesh_of, transforms = tree.instances
    assert isinstance(mesh_of, np.ndarray) and mesh_of.dtype == np.int32 and mesh_of.tolist() == [0, 0, 0]
    assert tree.stats["instances"] == 3


def test_the_placement_handed_out_cannot_be_edited_in_place():
    """`instances` gives the tree's own arrays, read-only (a helper's audit: an edit in place moved
    an instance the TLAS did not move, and a render then took a scene matching neither; a mesh
    index edited to 7 made `stats` raise IndexError). Placing is `place`'s."""
    tris = procedural.random_triangles(20, seed=1)
    tree = bvhlab.build(bvhlab.Scene(triangles=tris, instance_mesh=np.zeros(2, np.int32), instance_transforms=_eye(2)))
    mesh_of, transforms = tree.instances
    with pytest.raises(ValueError, match="read-only"):
        transforms[1, :, 3] = (50.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="read-only"):
        mesh_of[0] = 7
    assert tree.stats["instances"] == 2


def test_stats_handed_out_are_the_callers_own():
    """Each `stats` is a copy to its lists (an edit of one returned dict's list changed the next)."""
    tris = procedural.random_triangles(200, seed=1)
    flat = bvhlab.build(tris)
    flat.stats["nodes_per_depth"][0] = 12345
    assert flat.stats["nodes_per_depth"][0] == 1
    tree = bvhlab.build(bvhlab.Scene(triangles=tris, instance_mesh=np.zeros(2, np.int32), instance_transforms=_eye(2)))
    tree.stats["mesh_primitives"].append(999)
    assert tree.stats["mesh_primitives"] == [200]


def test_a_material_index_beyond_int32_is_refused_not_wrapped():
    tris = procedural.random_triangles(4, seed=1)
    scene = bvhlab.Scene(
        triangles=tris,
        meshes=[tris],
        materials=[bvhlab.Material(), bvhlab.Material()],
        instance_mesh=np.array([1]),
        instance_transforms=_eye(1),
    )
    with pytest.raises(ValueError, match="triangle 2 refers to material 4294967296"):
        scene.mesh_tri_material = [np.array([0, 1, 2**32, 0], np.int64)]


def test_a_scene_with_no_instances_is_an_empty_world():
    tris = procedural.random_triangles(20, seed=1)
    scene = bvhlab.Scene(triangles=tris, instance_mesh=np.zeros(0, np.int32), instance_transforms=_eye(0))
    assert scene.world_bounds() is None and scene.camera is None
    with pytest.raises(ValueError, match="no geometry"):
        scene.bounds()
    tree = bvhlab.build(scene)
    o, d = procedural.random_rays(tris, 100, seed=2)
    hits = tree.intersect(o, d)
    assert np.isinf(hits["t"]).all() and (hits["instance"] == -1).all()
    assert not tree.occluded(o, d).any()
    image, _ = bvhlab.render(scene, tree, 4, 3, backend="cpu")
    assert image.shape == (3, 4, 4) and np.isfinite(image).all()


def test_world_bounds_are_those_of_every_moved_corner():
    # against an independent computation: all 8 corners of each mesh's box, moved one by one
    rng = np.random.default_rng(5)
    meshes = [procedural.random_triangles(30, seed=k) for k in range(3)]
    n = 40
    transforms = rng.normal(size=(n, 3, 4)).astype(np.float32)
    mesh_of = rng.integers(0, 3, n).astype(np.int32)
    scene = bvhlab.Scene(triangles=meshes[0], meshes=meshes[1:], instance_mesh=mesh_of, instance_transforms=transforms)
    lo, hi = scene.bounds()
    corners = []
    for k, t in zip(mesh_of, transforms.astype(np.float64)):
        pts = meshes[k].reshape(-1, 3).astype(np.float64)
        box = np.array([pts.min(0), pts.max(0)])
        c = np.array([[box[(i >> a) & 1, a] for a in range(3)] for i in range(8)])
        corners.append(c @ t[:, :3].T + t[:, 3])
    corners = np.concatenate(corners)
    np.testing.assert_allclose(lo, corners.min(0), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(hi, corners.max(0), rtol=1e-12, atol=1e-12)


def test_tlas_leaf_lookups_refuse_indices_out_of_range():
    # a negative index was numpy's: the last instance's (or node's) leaf, silently
    tris = procedural.random_triangles(20, seed=1)
    tree = bvhlab.build(bvhlab.Scene(triangles=tris, instance_mesh=np.zeros(3, np.int32), instance_transforms=_eye(3)))
    nodes = tree.stats["tlas_nodes"]
    for bad in (-1, 3):
        with pytest.raises(ValueError, match="instance must be between 0 and 2"):
            tree.tlas_leaf_of(bad)
    for bad in (-1, nodes):
        with pytest.raises(ValueError, match=f"node must be between 0 and {nodes - 1}"):
            tree.tlas_leaf_instances(bad)
    leaves = [tree.tlas_leaf_of(i) for i in range(3)]
    assert all(i in tree.tlas_leaf_instances(leaf).tolist() for i, leaf in enumerate(leaves))
    # "must be between 0 and -1" where there are none (helper probe)
    empty = bvhlab.build(bvhlab.Scene(triangles=tris, instance_mesh=np.zeros(0, np.int32), instance_transforms=_eye(0)))
    with pytest.raises(ValueError, match="the tree has no instances$"):
        empty.tlas_leaf_of(0)
    with pytest.raises(ValueError, match="the tree has no instances: its TLAS has no nodes"):
        empty.tlas_leaf_instances(0)
