"""Pick Box on a two-level tree (issues 34, 35) under bpy 4.2, the add-on enabled in place: on an
instanced scene (Suzanne in a collection instanced four times, rotated, scaled, mirrored), a ray
given to the operator picks what a loop over the boxes the overlay shows finds for each Level
(TLAS, BLAS moved into the world, both); the steps cross between the levels; Frame This Box and
the panel's figures are the picked node's, its box in the world."""

import math

import blender_checks  # noqa: F401  (import path for the shared checks)
import harness  # before bpy
import numpy as np
import pytest
from oracles import box_entry
from test_addon_instancing import instanced_scene


@pytest.fixture(scope="module")
def built():
    import bpy

    harness.enable_addon_from_source()
    scene = instanced_scene()
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    addon = harness.addon().__name__
    state = __import__(addon + ".state", fromlist=["tree_for"])
    inspect = __import__(addon + ".ops_inspect", fromlist=["node_view"])
    import bvhlab

    assert isinstance(state.tree_for(scene).bvh, bvhlab.InstancedBvh)
    return scene, state, inspect


def _rays(count, seed):
    rng = np.random.default_rng(seed)
    origins = np.tile([0.5, -12.0, 5.0], (count, 1)) + rng.normal(0, 0.3, (count, 3))
    targets = rng.normal([0.0, 0.5, 0.0], [3.0, 2.0, 1.5], (count, 3))
    return origins, targets - origins


def _brute_force(tree, level, depths, leaves_only, o, d, t_hit):
    """What Pick Box must pick, by a loop over the boxes the overlay shows (shown_boxes): of those
    entered no later than the hit, BLAS boxes before TLAS boxes, the deepest, the first entered,
    the earliest shown."""
    from bvhlab.inspect.levels import shown_boxes

    shown = shown_boxes(tree, level, depths[0], depths[1], leaves_only)
    best = None
    for k in range(len(shown.lo)):
        t = box_entry(shown.lo[k].astype(float), shown.hi[k].astype(float), o, d)
        if math.isinf(t) or t > t_hit * (1 + 1e-4):
            continue
        key = (-int(shown.level[k]), -int(shown.depth[k]), t, k)
        best = key if best is None or key < best else best
    return None if best is None else shown.tree_node(best[3])


@pytest.mark.parametrize(
    "level, depths, leaves_only",
    [("both", (0, 40), False), ("tlas", (0, 40), False), ("blas", (3, 6), False), ("both", (0, 40), True)],
)
def test_a_ray_given_to_pick_box_picks_what_brute_force_finds(built, level, depths, leaves_only):
    import bpy

    scene, state, _ = built
    settings = scene.bvhlab
    settings.overlay_level, settings.overlay_leaves_only = level, leaves_only
    settings.overlay_depth_min, settings.overlay_depth_max = depths
    tree = state.tree_for(scene)
    shown = (depths[0], min(depths[1], tree.height - 1))
    boxes = blas = 0
    for o, d in zip(*_rays(25, 4)):
        o, d = np.float64(np.float32(o)), np.float64(np.float32(d))  # what the operator's float properties hold
        assert bpy.ops.bvhlab.pick_box(origin=o.tolist(), direction=d.tolist()) == {"FINISHED"}
        hit = tree.bvh.intersect(np.float32([o]), np.float32([d]), traversal="stack")
        expected = _brute_force(tree.bvh, level, shown, leaves_only, o, d, float(hit["t"][0]))
        picked = state.picked_node(scene)
        if expected is not None:
            assert picked == expected and state.picked[state.key(scene)][2] == "box"
            boxes += 1
            blas += picked.level == "blas"
        elif np.isfinite(hit["t"][0]):  # the leaf of the hit: in the hit instance's mesh tree
            assert picked.level == ("tlas" if level == "tlas" else "blas")
            if picked.level == "blas":
                assert picked.instance == hit["instance"][0]
        else:
            assert picked is None
    assert boxes >= 10 and (blas > 0) == (level != "tlas")


def test_steps_cross_the_levels_and_frame_uses_the_world_box(built):
    import bpy

    from bvhlab.inspect.levels import TreeNode
    from bvhlab.inspect.pick import node_world_box

    scene, state, inspect = built
    settings = scene.bvhlab
    settings.overlay_level, settings.overlay_leaves_only = "blas", True
    settings.overlay_depth_min, settings.overlay_depth_max = 0, 40
    tree = state.tree_for(scene).bvh
    mesh_of, _ = tree.instances
    for o, d in zip(*_rays(20, 8)):
        bpy.ops.bvhlab.pick_box(origin=o.tolist(), direction=d.tolist())
        if state.picked_node(scene) is not None:
            break
    leaf = state.picked_node(scene)
    assert leaf.level == "blas" and tree.meshes[int(mesh_of[leaf.instance])].is_leaf[leaf.node]
    data = tree.meshes[int(mesh_of[leaf.instance])].node_data()
    # up to the BLAS root, then to the TLAS leaf holding the instance
    node = leaf
    while node.node != 0:
        assert bpy.ops.bvhlab.pick_step(step="PARENT") == {"FINISHED"}
        up = state.picked_node(scene)
        assert up == TreeNode("blas", int(data.parent[node.node]), leaf.instance)
        node = up
    assert bpy.ops.bvhlab.pick_step(step="PARENT") == {"FINISHED"}
    tlas_leaf = state.picked_node(scene)
    assert tlas_leaf.level == "tlas" and leaf.instance in tree.tlas_leaf_instances(tlas_leaf.node)
    tlas = tree.tlas_node_data()
    world_lo, world_hi = tree.world_boxes()  # the TLAS's leaves are the instances' world boxes
    np.testing.assert_array_equal(tlas.lo[tlas_leaf.node], world_lo[leaf.instance])
    np.testing.assert_array_equal(tlas.hi[tlas_leaf.node], world_hi[leaf.instance])
    lo, hi = node_world_box(tree, TreeNode("blas", 0, leaf.instance))  # Arvo's box of the moved root
    centre = (world_lo[leaf.instance] + world_hi[leaf.instance]) / 2
    assert np.all(lo <= centre) and np.all(centre <= hi)
    # down again: Child 1 of a TLAS leaf is its first instance's BLAS root
    assert bpy.ops.bvhlab.pick_step(step="LEFT") == {"FINISHED"}
    assert state.picked_node(scene) == TreeNode("blas", 0, int(tree.tlas_leaf_instances(tlas_leaf.node)[0]))
    bpy.ops.bvhlab.pick_step(step="PARENT")
    assert bpy.ops.bvhlab.pick_step(step="SIBLING") == {"FINISHED"}  # the TLAS leaf's sibling, in the TLAS
    sibling = state.picked_node(scene)
    parent = int(tlas.parent[tlas_leaf.node])
    assert sibling.level == "tlas" and sibling.node in (tlas.left[parent], tlas.right[parent]) != tlas_leaf.node
    # the panel's figures and the highlight are the picked node's, its box in the world
    figures, n, lo, hi, name = inspect.node_view(state.tree_for(scene), sibling)
    assert figures is tlas and n == sibling.node and name.startswith("TLAS")
    np.testing.assert_array_equal(inspect.picked_box(scene)[0], tlas.lo[sibling.node])
    assert bpy.ops.bvhlab.frame_picked() in ({"CANCELLED"}, {"FINISHED"})  # headless: no viewport


def test_cost_panel_and_measures_of_the_whole_tree(built):
    """A two-level tree's Cost panel: the breakdown per depth adds up to its SAH cost; after Analyse
    Tree the costliest rows at a depth are TwoLevelNodeData.costliest's (checked against brute
    force in test_two_level_data) and Pick Node picks one of an instance's mesh tree; the overlay's
    table colours each shown box by its share of the whole tree's SAH (the TLAS root: all of it)."""
    import bpy

    from bvhlab.inspect.levels import TLAS, TreeNode, shown_boxes
    from bvhlab.inspect.two_level_data import TwoLevelNodeData

    scene, state, _ = built
    addon = harness.addon().__name__
    costs = __import__(addon + ".ops_costs", fromlist=["costliest"])
    overlay = __import__(addon + ".overlay", fromlist=["two_level_table"])
    tree = state.tree_for(scene)
    per_depth = costs.sah_per_depth(tree)
    assert np.isclose(sum(per_depth), tree.bvh.stats["sah_cost"], rtol=1e-9)
    assert bpy.ops.bvhlab.analyse_tree() == {"FINISHED"}
    data = tree.bvh.cached_node_data()
    assert isinstance(data, TwoLevelNodeData)
    depth = int(data.tlas.depth.max()) + 1  # below the TLAS: mesh tree nodes of several instances
    rows = costs.costliest(tree, depth)
    expected = data.costliest(costs.COSTLIEST, depth)
    assert len(rows) == len(expected) == costs.COSTLIEST
    assert [(n, i) for _, n, i in rows] == [(t.node, t.instance) for t, _ in expected]
    _, node, instance = next(r for r in rows if r[2] >= 0)
    assert bpy.ops.bvhlab.pick_node(node=node, instance=instance) == {"FINISHED"}
    assert state.picked_node(scene) == TreeNode("blas", node, instance)
    # the Inspect panel and Pick's report give the whole tree's figures, as the Cost panel's row
    # (they gave the mesh tree's own: depth 0 of 19.04 for a row of 12.05%)
    _, inspect = built[1], built[2]
    picked = TreeNode("blas", node, instance)
    whole = inspect.whole_tree_figures(tree, picked)
    assert whole["sah_share"] > 0 and whole["sah_share"] == pytest.approx(data.figures(picked)["sah_share"])
    assert whole["depth"] == data.depth(picked) == depth and whole["of"] == pytest.approx(data.sah_cost)
    assert whole["subtree_sah"] == pytest.approx(dict(expected)[picked])  # the row's cost
    with pytest.raises(RuntimeError, match="does not exist"):
        bpy.ops.bvhlab.pick_node(node=10**6, instance=instance)
    with pytest.raises(RuntimeError, match="instance 99 does not exist"):
        bpy.ops.bvhlab.pick_node(node=0, instance=99)
    table = overlay.two_level_table(tree.bvh, False, "sah_share", "both", (0, 255))
    shown = shown_boxes(tree.bvh, "both", 0, 255)
    np.testing.assert_array_equal(table.rows[:, 7], data.values(shown, "sah_share")[0])
    root = np.flatnonzero((shown.level == TLAS) & (shown.node == 0))
    assert table.rows[root, 7] == pytest.approx(1.0) and table.legend.high == pytest.approx(1.0)
