"""A two-level tree's statistics as a whole (bvhlab.two_level_stats, InstancedBvh.stats, issue 34):
what the add-on's panel, Export stats and Compare report for an instanced scene."""

import csv

import numpy as np

import bvhlab
from bvhlab.library import procedural
from bvhlab.stats_files import write_stats


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
    write_stats(tree.stats, {}, csv_file=path)
    rows = list(csv.reader(path.open()))
    assert ["mesh_instances", "0", "1"] in rows and ["mesh_instances", "1", "3"] in rows
    assert ["instances", "", "4"] in rows


def _per_depth_by_walk(tlas, meshes, mesh_of) -> dict:
    """The SAH cost by depth in the tree TLAS and BLASes make together, by a recursive walk of the
    node arrays: a TLAS leaf's BLAS root takes the leaf's place (its depth). Each node costs
    A(n)/A(root) (internal) or A(n)/A(root)·N (leaf); a BLAS node's area is taken relative to its
    own root and scaled by A(instance)/A(TLAS root)."""
    out: dict = {}

    def area(lo, hi):
        e = np.maximum(hi.astype(np.float64) - lo.astype(np.float64), 0.0)
        return 2.0 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0])

    def walk_blas(tree, i, depth, scale):
        nodes = tree.nodes
        n = nodes[i]
        internal = bool(n["info"] & bvhlab.bvh.NODE_INTERNAL_BIT)
        root = area(nodes[0]["lo"], nodes[0]["hi"])
        out[depth] = out.get(depth, 0.0) + scale * area(n["lo"], n["hi"]) / root * (1 if internal else n["info"])
        if internal:
            walk_blas(tree, i + 1, depth + 1, scale)
            walk_blas(tree, int(n["index"]), depth + 1, scale)

    tlas_nodes = tlas.nodes
    tlas_root = area(tlas_nodes[0]["lo"], tlas_nodes[0]["hi"])

    def walk_tlas(i, depth):
        n = tlas_nodes[i]
        a = area(n["lo"], n["hi"]) / tlas_root
        if n["info"] & bvhlab.bvh.NODE_INTERNAL_BIT:
            out[depth] = out.get(depth, 0.0) + a
            walk_tlas(i + 1, depth + 1)
            walk_tlas(int(n["index"]), depth + 1)
        else:
            assert n["info"] == 1  # one instance per TLAS leaf
            instance = int(tlas.refs[n["index"]])
            walk_blas(meshes[mesh_of[instance]], 0, depth, a)

    walk_tlas(0, 0)
    return out


def test_sah_cost_per_depth_of_a_two_level_tree_against_a_walk_of_its_nodes():
    """Compare's per-depth SAH of a two-level tree (two_level_sah_cost_per_depth): by depth in the
    tree TLAS and BLASes make together, against a recursive walk of the node arrays; the entries
    add up to the two-level SAH cost, and one identity instance gives the flat tree's entries."""
    from bvhlab.compare.tree_stats import sah_cost_per_depth
    from bvhlab.two_level_stats import two_level_sah_cost_per_depth

    tree = bvhlab.build(_scene(9))
    s = tree.stats
    mesh_of = tree.instances[0]
    got = two_level_sah_cost_per_depth(
        tree.tlas, mesh_of, [sah_cost_per_depth(m) for m in tree.meshes], s["mesh_sah_cost"]
    )
    walked = _per_depth_by_walk(tree.tlas, tree.meshes, mesh_of)
    want = [walked.get(d, 0.0) for d in range(max(walked) + 1)]
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
    assert len(got) <= s["height"] - 1  # TLAS leaves replaced by BLAS roots
    assert np.isclose(sum(got), s["sah_cost"], rtol=1e-6), (sum(got), s["sah_cost"])
    assert sorted(tree.tlas.refs.tolist()) == list(range(9))  # the TLAS's references: instances

    cloud = procedural.random_triangles(300, size=0.2, seed=7)
    identity = np.eye(4, dtype=np.float32)[None, :3]
    one = bvhlab.build(bvhlab.Scene(cloud, instance_mesh=np.array([0]), instance_transforms=identity))
    flat = sah_cost_per_depth(bvhlab.build(cloud))
    per_depth = two_level_sah_cost_per_depth(one.tlas, [0], [sah_cost_per_depth(one.meshes[0])], [0.0])
    np.testing.assert_allclose(per_depth, flat, rtol=1e-9)
