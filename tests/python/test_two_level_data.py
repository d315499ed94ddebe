"""A two-level tree's node figures as one tree (bvhlab.inspect.two_level_data, issue 35 on issue
34's trees): checked against a recursive walk of the node arrays, against brute force over every
(instance, node) pair, against the per-depth SAH split Compare shows, and against the scale of
each instance for EPO."""

import numpy as np
import pytest

import bvhlab
from bvhlab.compare.tree_stats import sah_cost_per_depth
from bvhlab.inspect.levels import BLAS, TLAS, TreeNode, shown_boxes
from bvhlab.inspect.measures import MEASURES
from bvhlab.inspect.two_level_data import TwoLevelNodeData
from bvhlab.library import procedural
from bvhlab.two_level_stats import box_areas, two_level_sah_cost_per_depth


def _scene(instances: int = 9, seed: int = 3) -> bvhlab.Scene:
    cloud = procedural.random_triangles(300, size=0.2, seed=seed)
    knot = procedural.torus_knot(1200)
    rng = np.random.default_rng(seed)
    transforms = np.zeros((instances, 3, 4), np.float32)
    transforms[:, :3, :3] = np.eye(3) * rng.uniform(0.4, 2.5, (instances, 1, 1))
    transforms[:, :, 3] = rng.uniform(-6, 6, (instances, 3))
    transforms[2, :3, :3] = np.diag([1.5, 0.5, 2.0])  # a non-uniform scale
    mesh_of = np.array([0, 1, 1, 0, 1, 1, 0, 1, 1][:instances])
    return bvhlab.Scene(triangles=cloud, meshes=[knot], instance_mesh=mesh_of, instance_transforms=transforms)


@pytest.fixture(scope="module")
def tree():
    return bvhlab.build(_scene(), max_leaf_size=4)


def _walk(bvh, data: TwoLevelNodeData, node: int, root_area: float) -> tuple[float, int]:
    """(the whole tree's SAH cost under TLAS node `node`, primitives under it), recursively: an
    inner node's A/A(R), and for each instance of a leaf A(world box)/A(R) × its mesh's SAH cost."""
    tlas = data.tlas
    if tlas.left[node] < 0:
        lo, hi = bvh.world_boxes()
        cost, prims = 0.0, 0
        for i in bvh.tlas_leaf_instances(node):
            mesh = bvh.meshes[int(bvh.instances[0][i])]
            cost += box_areas(lo[i : i + 1], hi[i : i + 1])[0] / root_area * mesh.stats["sah_cost"]
            prims += mesh.stats["primitives"]
        return cost, prims
    left, right = (_walk(bvh, data, int(c), root_area) for c in (tlas.left[node], tlas.right[node]))
    return float(tlas.area[node]) / root_area + left[0] + right[0], left[1] + right[1]


def test_subtree_costs_and_counts_equal_a_recursive_walk(tree):
    data = tree.node_data()
    root = float(data.tlas.area[0])
    for node in range(len(data.tlas)):
        cost, prims = _walk(tree, data, node, root)
        assert data.tlas_subtree_sah[node] == pytest.approx(cost, rel=1e-9), node
        assert data.tlas_prims[node] == prims
    assert data.sah_cost == pytest.approx(tree.stats["sah_cost"], rel=1e-9)
    assert data.tlas_prims[0] == tree.stats["primitives_flattened"]


def _every_node(tree, data):
    """Every node of the whole tree (TLAS inner nodes, each instance's mesh nodes) with its cost
    and depth, by brute force."""
    rows = []
    for n in np.flatnonzero(data.tlas.left >= 0):
        rows.append((TreeNode("tlas", int(n)), float(data.tlas_subtree_sah[n]), int(data.tlas.depth[n])))
    lo, hi = tree.world_boxes()
    areas = box_areas(lo, hi) / float(data.tlas.area[0])
    for i, m in enumerate(tree.instances[0]):
        mesh = tree.meshes[int(m)].node_data()
        leaf_depth = int(data.tlas.depth[tree.tlas_leaf_of(i)])
        for b in range(len(mesh)):
            rows.append((TreeNode("blas", b, i), areas[i] * mesh.subtree_sah[b], leaf_depth + int(mesh.depth[b])))
    return rows


@pytest.mark.parametrize("depth", [None, 0, 1, 3, 6])
def test_costliest_equals_brute_force(tree, depth):
    data = tree.node_data()
    rows = [r for r in _every_node(tree, data) if depth is None or r[2] == depth]
    expected = sorted(r[1] for r in rows)[::-1][:5]
    got = data.costliest(5, depth)
    np.testing.assert_allclose([c for _, c in got], expected, rtol=1e-9)
    for node, cost in got:
        assert data.subtree_sah(node) == pytest.approx(cost, rel=1e-9)
        if depth is not None:
            assert data.depth(node) == depth


def test_depths_agree_with_the_per_depth_split(tree):
    """Each node's own SAH term summed by its depth in the whole tree gives Compare's per-depth
    split (two_level_sah_cost_per_depth): the two agree on where a mesh tree sits."""
    data = tree.node_data()
    per_depth = two_level_sah_cost_per_depth(
        tree.tlas, tree.instances[0], [sah_cost_per_depth(m) for m in tree.meshes], tree.stats["mesh_sah_cost"]
    )
    own = np.zeros(len(per_depth) + 4)
    for n in np.flatnonzero(data.tlas.left >= 0):
        own[data.tlas.depth[n]] += data.tlas.sah_term[n]
    for i in range(len(data.mesh_of)):
        mesh = data.mesh_data(i)
        for b in range(len(mesh)):
            own[data.depth(TreeNode("blas", b, i))] += data.weight[i] * mesh.sah_term[b]
    np.testing.assert_allclose(own[: len(per_depth)], per_depth, rtol=1e-9, atol=1e-12)
    assert not own[len(per_depth) :].any()


@pytest.mark.parametrize("measure", list(MEASURES))
def test_shown_boxes_values(tree, measure):
    data = tree.node_data()
    shown = shown_boxes(tree, "both", 0, 255)
    raw = data.raw(shown, measure)
    for k in range(len(raw)):
        node = shown.tree_node(k)
        if shown.level[k] == TLAS:
            expected = {
                "sah_share": data.tlas_subtree_sah[node.node] / data.sah_cost,
                "leaf_size": data.tlas_prims[node.node],
                "child_overlap": data.tlas.child_overlap[node.node],
                "epo": 0.0,
            }[measure]
        else:
            mesh = data.mesh_data(node.instance)
            expected = {
                "sah_share": data.subtree_sah(node) / data.sah_cost,
                "leaf_size": mesh.prim_count[node.node],
                "child_overlap": mesh.child_overlap[node.node],
                "epo": data.epo_weight[node.instance] * mesh.epo[node.node] / data.epo_total,
            }[measure]
        assert raw[k] == pytest.approx(expected, rel=1e-9, abs=1e-15), (k, node)
    values, legend = data.values(shown, measure)
    assert values.dtype == np.float32 and 0 <= values.min() and values.max() <= 1
    if measure == "sah_share":  # the root's share is the whole tree's, so it is the hottest
        assert raw[(shown.level == TLAS) & (shown.node == 0)] == pytest.approx(1.0)
        assert values.max() == pytest.approx(1.0) and legend.high == pytest.approx(1.0)
    if measure == "epo":  # the BLAS shares over every instance's nodes add up to 1
        assert raw[shown.level == BLAS].sum() == pytest.approx(1.0, rel=1e-9)


def test_epo_weights_follow_each_instances_scale():
    """Two instances of one mesh, one moved and one scaled by 2: the scaled one's surface is 4×, so
    its nodes hold 4/5 of the scene's EPO and the moved one's 1/5, node for node."""
    knot = procedural.torus_knot(800)
    transforms = np.zeros((2, 3, 4), np.float32)
    transforms[0, :3, :3] = np.eye(3)
    transforms[0, :, 3] = (5, 0, 0)
    transforms[1, :3, :3] = 2 * np.eye(3)
    scene = bvhlab.Scene(triangles=knot, instance_mesh=[0, 0], instance_transforms=transforms)
    tree = bvhlab.build(scene)
    data = tree.node_data()
    mesh = tree.meshes[0].node_data()
    assert mesh.surface_area == pytest.approx(_area(knot), rel=1e-6)
    shown = shown_boxes(tree, "blas", 0, 255)
    raw = data.raw(shown, "epo")
    for i, share in ((0, 1 / 5), (1, 4 / 5)):
        at = shown.instance == i
        np.testing.assert_allclose(raw[at], share * mesh.epo[shown.node[at]] / mesh.epo_cost, rtol=1e-5)


def test_one_identity_instance_is_its_flat_tree():
    knot = procedural.torus_knot(900)
    one = bvhlab.build(
        bvhlab.Scene(triangles=knot, instance_mesh=[0], instance_transforms=np.eye(4, dtype=np.float32)[None, :3])
    )
    flat = bvhlab.build(bvhlab.Scene(triangles=knot)).node_data()
    data = one.node_data()
    assert data.weight[0] == pytest.approx(1.0, rel=1e-6)
    assert data.sah_cost == pytest.approx(flat.sah_cost, rel=1e-6)
    shown = shown_boxes(one, "blas", 0, 255)
    np.testing.assert_allclose(data.raw(shown, "sah_share"), flat.sah_share[shown.node], rtol=1e-5)


def test_cached_node_data_never_computes(tree):
    fresh = bvhlab.build(_scene(seed=8))
    assert fresh.cached_node_data() is None
    made = fresh.node_data()
    assert fresh.cached_node_data() is made
    fresh.place(fresh.instances[0], fresh.instances[1] * np.float32(1.0))  # a new TLAS: joins made again
    again = fresh.cached_node_data()
    assert again is not None and again is not made
    assert again.sah_cost == pytest.approx(made.sah_cost, rel=1e-9)


def _area(tris: np.ndarray) -> float:
    t = tris.astype(np.float64)
    return float(0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum())
