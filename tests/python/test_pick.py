"""Picking a box with a ray (bvhlab.inspect.pick) against brute force over the shown boxes: every
box's entry distance by a plain slab test per node, the same rule written as a loop."""

import numpy as np
import pytest
from oracles import box_entry, pick_by_brute_force

import bvhlab
from bvhlab.inspect.pick import entry_distances, pick
from bvhlab.library import procedural


@pytest.fixture(scope="module")
def tree():
    scene = bvhlab.Scene(triangles=procedural.torus_knot(3000))
    return bvhlab.build(scene, method="sah", max_leaf_size=4)


def _rays(count, seed):
    rng = np.random.default_rng(seed)
    origins = rng.normal(0, 4, (count, 3))
    targets = rng.normal(0, 0.6, (count, 3))
    return origins, targets - origins


@pytest.mark.parametrize("depths, leaves_only", [((0, 255), False), ((3, 5), False), ((6, 6), False), ((0, 255), True)])
def test_pick_is_the_deepest_shown_box_entered_first_before_the_hit(tree, depths, leaves_only):
    data = tree.node_data()
    picked_boxes = 0
    for o, d in zip(*_rays(60, 7)):
        got = pick(tree, o, d, depths, leaves_only=leaves_only)
        expected = pick_by_brute_force(data, o, d, got.t_hit, depths, leaves_only)
        if expected is not None:
            assert (got.node, got.how) == (expected, "box"), (o, d)
            picked_boxes += 1
        else:
            assert got.how in ("hit leaf", "nothing")
    assert picked_boxes >= 20, "most rays aim at the knot"


def test_a_ray_that_reaches_no_shown_box_picks_the_leaf_it_hits(tree):
    data = tree.node_data()
    deepest = int(data.depth.max())
    for o, d in zip(*_rays(40, 3)):
        got = pick(tree, o, d, (deepest + 1, deepest + 1))  # a range below every box
        hit = tree.intersect(np.float32([o]), np.float32([d]), traversal="stack")
        if np.isinf(hit["t"][0]):
            assert got.node is None and got.how == "nothing"
        else:
            assert got.how == "hit leaf" and data.left[got.node] < 0
            record = tree.trace_ray(np.float32(o), np.float32(d))
            assert got.node == record.hit_leaf and record.prim == hit["prim"][0]


def test_entry_distances_equal_the_slab_test_of_each_box(tree):
    data = tree.node_data()
    o, d = np.array([0.3, -5.0, 0.2]), np.array([0.0, 1.0, 0.05])  # x parallel to the slabs
    t = entry_distances(data, o, d)
    expected = [box_entry(data.lo[n].astype(float), data.hi[n].astype(float), o, d) for n in range(len(data))]
    np.testing.assert_allclose(t, expected, rtol=1e-12)
    assert np.isfinite(t[0]) and np.isinf(t).any()


@pytest.mark.parametrize("o, d", [((0, 0, 0), (0, 0, 0)), ((np.nan, 0, 0), (1, 0, 0)), ((0, 0, 0), (np.inf, 0, 0))])
def test_bad_rays_are_refused(tree, o, d):
    with pytest.raises(ValueError, match="pick ray"):
        pick(tree, o, d)


def test_a_ray_that_misses_everything_picks_nothing(tree):
    """A ray past the whole tree hits nothing and enters no box: nothing is picked (a miss's
    infinite hit distance is no licence to pick boxes the ray never enters)."""
    lo, hi = tree.node_data().lo[0], tree.node_data().hi[0]
    origin = hi + 5.0
    for direction in ((1.0, 0.0, 0.0), (0.3, 1.0, 0.2), (1.0, 1.0, 1.0)):
        got = pick(tree, origin, direction)
        assert (got.node, got.how) == (None, "nothing") and np.isinf(got.t_hit)
    assert np.all(lo < origin)


@pytest.mark.parametrize("distance", [10.0, 1e3, 1e4])
def test_a_box_behind_the_hit_is_not_picked_from_far_away(distance):
    """A wall, and small triangles 0.02-0.05 behind it: the ray from `distance` away picks the
    wall's box, entered at the hit. A slack relative to the distance (1e-4) took a box 0.018
    behind the wall from 1,000 and 10,000 away (an orthographic view's mouse ray starts far)."""
    wall = np.array([[[-50, -50, 0], [50, -50, 0], [0, 50, 0]]], np.float32)
    rng = np.random.default_rng(0)
    behind = rng.uniform([-1, -1, 0.02], [1, 1, 0.05], (400, 1, 3)) + rng.normal(0, 0.003, (400, 3, 3))
    bvh = bvhlab.build(np.concatenate([wall, behind.astype(np.float32)]), max_leaf_size=1)
    picked = pick(bvh, np.array([0.1, 0.1, -distance]), np.array([0.0, 0.0, 1.0]), (0, 255))
    assert picked.t_hit == pytest.approx(distance)
    assert picked.t_enter <= picked.t_hit  # not a box behind the wall


def test_a_float64_origin_picks_as_its_float32_ray_traces():
    """The boxes' entries were measured from the float64 origin, the hit by the float32 trace: a
    float32 step of the origin apart (a wall 0.01-0.5 from x = 1,000 missed in 99 of 200 picks)."""
    rng = np.random.default_rng(3)
    wall = np.array([[[1000.3, -50, -50], [1000.3, 50, -50], [1000.3, 0, 50]]], np.float32)
    bvh = bvhlab.build(wall)
    for gap in rng.uniform(0.01, 0.5, 200):
        origin = np.array([1000.3 - gap + 1e-9, rng.uniform(-1, 1), rng.uniform(-1, 1)])
        picked = pick(bvh, origin, np.array([1.0, 0.0, 0.0]), (0, 255))
        assert picked.node == 0 and picked.how == "box", (gap, picked)  # entered, not the hit's fallback


def test_the_traced_picture_picks_through_a_surface_hidden_from_camera_rays():
    """In the Rendered viewport the tracer passes a surface hidden from camera rays by (the
    add-on gives pick the scene there): a ray through a hidden sphere to a wall reaches the wall,
    and picks the wall's leaf at the wall's depth; in Blender's own drawing (no scene) it reaches
    the sphere and picks the sphere's leaf, as before."""
    wall = np.array([[[-3, -3, -5], [3, -3, -5], [3, 3, -5]], [[-3, -3, -5], [3, 3, -5], [-3, 3, -5]]], np.float32)
    scene = bvhlab.Scene(
        triangles=wall,
        spheres=np.array([[0, 0, 0, 1]], np.float32),
        materials=[bvhlab.Material(), bvhlab.Material(hidden_from=bvhlab.Rays.CAMERA)],
        tri_material=np.array([0, 0], np.int32),
        sphere_material=np.array([1], np.int32),
    )
    bvh = bvhlab.build(scene, max_leaf_size=1)
    data = bvh.node_data()
    origin, direction = (0.1, 0.2, 5.0), (0.0, 0.0, -1.0)
    wall_hit = bvhlab.build(wall).intersect(np.float32([origin]), np.float32([direction]))
    seen = pick(bvh, origin, direction, leaves_only=True, scene=scene)
    drawn = pick(bvh, origin, direction, leaves_only=True)
    assert drawn.t_hit == pytest.approx(5 - np.sqrt(1 - 0.1**2 - 0.2**2), abs=1e-5)  # the sphere
    assert seen.t_hit == wall_hit["t"][0]  # the wall, as a tree without the sphere has it
    sphere_slot = int(np.flatnonzero(bvh.refs & bvhlab.bvh.REF_SPHERE_BIT)[0])
    sphere_leaf = int(np.flatnonzero((data.left < 0) & (bvh.nodes["index"] == sphere_slot))[0])  # leaves of one
    assert drawn.node == sphere_leaf, "in Blender's drawing the sphere's leaf is entered first"
    wall_depths = {int(data.depth[n]) for n in np.flatnonzero(data.left < 0) if n != sphere_leaf}
    only_walls = max(wall_depths - {int(data.depth[sphere_leaf])})  # wall leaves, not the sphere's
    seen = pick(bvh, origin, direction, (only_walls, only_walls), leaves_only=True, scene=scene)
    drawn = pick(bvh, origin, direction, (only_walls, only_walls), leaves_only=True)
    assert (drawn.node, drawn.how) == (sphere_leaf, "hit leaf")  # no wall box before the sphere
    assert seen.how == "box" and seen.t_enter == pytest.approx(10.0, abs=1e-4)
    assert int(data.depth[seen.node]) == only_walls and data.left[seen.node] < 0
