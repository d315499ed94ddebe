"""A two-level tree's statistics as a whole (bvhlab.two_level_stats, InstancedBvh.stats, issue 34):
what the add-on's panel, Export stats and Compare report for an instanced scene."""

import csv

import numpy as np

import bvhlab
from bvhlab.library import procedural
from bvhlab.stats_files import write_stats_csv


def _scene(instances: int = 6) -> bvhlab.Scene:
    cloud = procedural.random_triangles(200, size=0.15, seed=5)
    knot = procedural.torus_knot(1500)
    rng = np.random.default_rng(2)
    transforms = np.zeros((instances, 3, 4), np.float32)
    transforms[:, :3, :3] = np.eye(3) * rng.uniform(0.5, 2.0, (instances, 1, 1))
    transforms[:, :, 3] = rng.uniform(-5, 5, (instances, 3))
    mesh_of = np.array([0] + [1] * (instances - 1))
    transforms[0] = np.eye(4, dtype=np.float32)[:3]
    return bvhlab.Scene(triangles=cloud, meshes=[knot], instance_mesh=mesh_of, instance_transforms=transforms)


def test_one_identity_instance_has_the_flat_trees_figures(small_scene):
    """A two-level tree of one identity instance: the SAH cost, primitives and memory beyond the TLAS
    are the flat tree's."""
    tris, spheres = small_scene
    identity = np.eye(4, dtype=np.float32)[None, :3]
    one = bvhlab.build(bvhlab.Scene(tris, spheres, instance_mesh=np.array([0]), instance_transforms=identity))
    flat = bvhlab.build(bvhlab.Scene(tris, spheres))
    assert isinstance(one, bvhlab.InstancedBvh)
    s, f = one.stats, flat.stats
    assert np.isclose(s["sah_cost"], f["sah_cost"], rtol=1e-6), (s["sah_cost"], f["sah_cost"])
    assert s["primitives"] == s["primitives_flattened"] == f["primitives"]
    assert s["memory_bytes"] - s["tlas_memory_bytes"] == f["memory_bytes"]
    assert s["height"] == f["height"] + s["tlas_height"]


def test_stored_against_flattened_and_per_mesh_lists():
    tree = bvhlab.build(_scene(6))
    s = tree.stats
    assert (s["instances"], s["meshes"]) == (6, 2)
    knot = len(_scene(6).meshes[0])
    assert s["mesh_instances"] == [1, 5] and s["mesh_primitives"] == [200, knot]
    assert s["triangles"] == 200 + s["mesh_primitives"][1]
    assert s["triangles_flattened"] == 200 + 5 * s["mesh_primitives"][1]
    assert s["nodes"] == s["tlas_nodes"] + sum(m.stats["nodes"] for m in tree.meshes)
    # the two-level SAH: the TLAS's, with each instance leaf's one primitive replaced by its mesh's cost
    lo, hi = tree.world_boxes()
    e = hi.astype(np.float64) - lo
    area = 2 * (e[:, 0] * e[:, 1] + e[:, 1] * e[:, 2] + e[:, 2] * e[:, 0])
    r = hi.max(0).astype(np.float64) - lo.min(0)
    root = 2 * (r[0] * r[1] + r[1] * r[2] + r[2] * r[0])
    blas = np.array(s["mesh_sah_cost"])[[0, 1, 1, 1, 1, 1]]
    assert np.isclose(s["sah_cost"], s["tlas_sah_cost"] + np.sum(area / root * (blas - 1)), rtol=1e-9)


def test_stats_csv_writes_one_row_per_mesh(tmp_path):
    tree = bvhlab.build(_scene(4))
    path = tmp_path / "stats.csv"
    write_stats_csv(path, tree.stats)
    rows = list(csv.reader(path.open()))
    assert ["mesh_instances", "0", "1"] in rows and ["mesh_instances", "1", "3"] in rows
    assert ["instances", "", "4"] in rows
