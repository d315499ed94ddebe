"""Bvh.intersect against two independent oracles: a float64 numpy brute force, and Embree."""

import numpy as np
import pytest
from oracles import brute_force

import bvhlab
from bvhlab.library import procedural


@pytest.mark.parametrize("method", bvhlab.METHODS)
@pytest.mark.parametrize("traversal", bvhlab.TRAVERSALS)
def test_equals_brute_force(small_scene, method, traversal):
    tris, spheres = small_scene
    bvh = bvhlab.build(tris, spheres, method=method, max_leaf_size=3)
    o, d = procedural.random_rays(tris, 1500, seed=11)
    d[::7, 0] = 0  # axis-parallel components
    got = bvh.intersect(o, d, traversal=traversal)
    want_t, want_id, want_kind = brute_force(tris, spheres, o, d)
    assert np.array_equal(np.isfinite(got["t"]), np.isfinite(want_t))
    hit = np.isfinite(want_t)
    assert hit.mean() > 0.2, "the rays must hit something to test anything"
    np.testing.assert_allclose(got["t"][hit], want_t[hit], rtol=1e-4)
    same = (got["prim"] == want_id) & (got["kind"] == want_kind)
    # a different primitive only where two lie at (nearly) the same distance
    assert np.all(same | ~hit)
    assert np.all(got["prim"][~hit] == -1)


def test_traversals_agree_exactly(knot_mesh):
    bvh = bvhlab.build(knot_mesh, method="mean")
    o, d = procedural.random_rays(knot_mesh, 20000, seed=2)
    a = bvh.intersect(o, d, traversal="stack")
    for other in ("stackless", "wide"):
        b = bvh.intersect(o, d, traversal=other)
        for k in ("t", "prim", "kind", "u", "v"):
            np.testing.assert_array_equal(a[k], b[k])


def test_barycentrics_reconstruct_the_hit_point(knot_mesh):
    bvh = bvhlab.build(knot_mesh)
    o, d = procedural.camera_rays(knot_mesh, 64, 48)
    h = bvh.intersect(o, d)
    hit = h["prim"] >= 0
    assert hit.sum() > 200
    tri = knot_mesh[h["prim"][hit]].astype(np.float64)
    u, v = h["u"][hit, None], h["v"][hit, None]
    p_bary = tri[:, 0] * (1 - u - v) + tri[:, 1] * u + tri[:, 2] * v
    p_ray = o[hit] + d[hit] * h["t"][hit, None]
    np.testing.assert_allclose(p_bary, p_ray, atol=1e-4)


def test_tmin_tmax():
    tris = np.array([[[-1, -1, z], [3, -1, z], [-1, 3, z]] for z in range(10)], np.float32)
    bvh = bvhlab.build(tris)
    o = np.array([[0, 0, -5]], np.float32)
    d = np.array([[0, 0, 1]], np.float32)
    assert bvh.intersect(o, d, tmin=7.5)["t"][0] == 8.0
    assert bvh.intersect(o, d, tmax=4.5)["prim"][0] == -1


embreex = pytest.importorskip("embreex", reason="embreex is installed by make test")


def embree_hits(tris, origins, dirs):
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh

    scene = rtcs.EmbreeScene()
    TriangleMesh(scene, tris)
    out = scene.run(origins, dirs, output=1)
    t = np.where(out["primID"] >= 0, out["tfar"], np.inf)
    return t, out["primID"]


@pytest.mark.parametrize("rays", ["camera", "random"])
def test_agrees_with_embree_on_a_real_mesh(knot_mesh, rays):
    assert len(knot_mesh) >= 50000
    if rays == "camera":
        o, d = procedural.camera_rays(knot_mesh, 320, 240)
    else:
        o, d = procedural.random_rays(knot_mesh, 100000, seed=7)
    want_t, want_id = embree_hits(knot_mesh, o, d)
    assert np.isfinite(want_t).sum() > 5000
    for method in ("median", "mean", "sah"):
        got = bvhlab.build(knot_mesh, method=method).intersect(o, d)
        same_hit = np.isfinite(got["t"]) == np.isfinite(want_t)
        both = np.isfinite(got["t"]) & np.isfinite(want_t)
        close = np.abs(got["t"][both] - want_t[both]) <= 1e-4 * want_t[both]
        assert same_hit.mean() >= 0.9999, f"{method}: {np.count_nonzero(~same_hit)} rays disagree on hit/miss"
        assert close.mean() >= 0.9999, f"{method}: {np.count_nonzero(~close)} rays disagree on t"
        assert (got["prim"][both] == want_id[both]).mean() >= 0.999


@pytest.mark.parametrize("traversal", bvhlab.TRAVERSALS)
def test_rays_along_the_edges_of_a_square_hit(traversal):
    """Issue 8.6: rays straight down on the x = 1 / y = 1 edges of the unit square lie in the root
    box's upper faces and were dropped, while those on x = 0 / y = 0 hit."""
    square = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0]], [[0, 0, 0], [1, 1, 0], [0, 1, 0]]], np.float32)
    grid = np.array([(x, y, 1.0) for x in (0, 0.5, 1) for y in (0, 0.5, 1)], np.float32)
    down = np.tile(np.array([0, 0, -1], np.float32), (len(grid), 1))
    hits = bvhlab.build(square).intersect(grid, down, traversal=traversal)
    np.testing.assert_array_equal(hits["t"], 1.0)


def test_every_traversal_picks_the_same_primitive_on_ties():
    """Issue 8.7: on equal distances the smaller primitive index wins, whatever the traversal."""
    rng = np.random.default_rng(5)
    copies = np.tile(np.array([[[0, 0, 0], [4, 0, 0], [0, 4, 0]]], np.float32), (30, 1, 1))
    tris = np.concatenate([procedural.random_triangles(300, seed=3) * 8 - 4, copies]).astype(np.float32)
    tris = np.ascontiguousarray(tris[rng.permutation(len(tris))])
    first_copy = int(np.flatnonzero((tris == copies[0]).all(axis=(1, 2)))[0])
    o = np.column_stack([rng.uniform(0.1, 1.5, 60), rng.uniform(0.1, 1.5, 60), np.full(60, 9.0)]).astype(np.float32)
    d = np.tile(np.array([0, 0, -1], np.float32), (60, 1))
    for method in ("sah", "median", "lbvh"):
        bvh = bvhlab.build(tris, method=method)
        results = [bvh.intersect(o, d, traversal=t)["prim"] for t in bvhlab.TRAVERSALS]
        for prim in results:
            covered = prim >= 0
            assert covered.sum() > 40
            np.testing.assert_array_equal(prim, results[0])
            assert (prim[np.isin(prim, np.flatnonzero((tris == copies[0]).all(axis=(1, 2))))] == first_copy).all()


def test_a_tie_at_a_shared_vertex_goes_to_the_smaller_index_in_every_traversal():
    tris = np.array(
        [
            [[-16, -16, -16], [-8.125, -16, -16], [-10, -13, -16]],
            [[-10.5625, -9.375, -11.9375], [-10, -16, -16], [-16, -16, -16]],
        ],
        np.float32,
    )
    o = np.full((1, 3), -8, np.float32)  # straight at the shared vertex (-16, -16, -16)
    bvh = bvhlab.build(tris, method="median")
    prims = {t: int(bvh.intersect(o, o, traversal=t)["prim"][0]) for t in bvhlab.TRAVERSALS}
    assert prims == {"stack": 0, "stackless": 0, "wide": 0}


def test_rays_beside_a_small_distant_sphere_miss_it():
    """A sphere of radius 1 mm 100 m away: rays passing 2 to 50 radii beside it were hits."""
    r, distance = 1e-3, 100.0
    beside = np.array([2, 5, 10, 20, 50]) * r
    o = np.zeros((len(beside), 3), np.float32)
    d = np.column_stack([np.full(len(beside), distance), beside, np.zeros(len(beside))]).astype(np.float32)
    one = bvhlab.build(np.zeros((0, 3, 3), np.float32), np.array([[distance, 0, 0, r]], np.float32))
    two = bvhlab.build(
        np.zeros((0, 3, 3), np.float32),
        np.array([[distance, 0, 0, r], [distance, 0.2, 0, r]], np.float32),
        max_leaf_size=2,
        method="median",
    )
    through = np.array([[distance, 0, 0], [distance, 0.5 * r, 0]], np.float32)  # the centre, half a radius off
    for bvh in (one, two):  # a lone sphere (its box culls in stack and stackless) and two in a leaf
        for traversal in bvhlab.TRAVERSALS:
            assert np.all(bvh.intersect(o, d, traversal=traversal)["prim"] == -1), traversal
            hits = bvh.intersect(np.zeros((2, 3), np.float32), through, traversal=traversal)
            assert np.all(hits["prim"] == 0) and np.all(hits["kind"] == 1), traversal
            np.testing.assert_allclose(hits["t"], [1 - r / distance, 1 - np.sqrt(0.75) * r / distance], rtol=1e-6)


def test_nodes_visited_only_where_asked_and_the_same_hits_either_way(knot_mesh):
    """Counting keeps each ray on its own walk; without it the wide batch takes a camera's rays
    through the tree eight at a time: the same hits, bit for bit, on a camera's rays and on random
    ones, as the binary tree's walk gives."""
    bvh = bvhlab.build(knot_mesh)
    camera = procedural.camera_rays(knot_mesh, 160, 120)
    for o, d in (camera, procedural.random_rays(knot_mesh, 20000, seed=4)):
        fast, counted = bvh.intersect(o, d), bvh.intersect(o, d, nodes_visited=True)
        stack = bvh.intersect(o, d, traversal="stack", nodes_visited=True)
        assert "nodes_visited" not in fast and counted["nodes_visited"].dtype == np.uint32
        assert 0.1 < np.isfinite(fast["t"]).mean() < 0.9, "hits and misses both, to test anything"
        for k in ("t", "prim", "kind", "u", "v"):
            np.testing.assert_array_equal(fast[k], counted[k])
            np.testing.assert_array_equal(fast[k], stack[k])
        assert counted["nodes_visited"].sum() > len(o)  # counted: more than the root a ray
    with pytest.raises(TypeError, match="nodes_visited must be True or False, got 'yes'"):
        bvh.intersect(*camera, nodes_visited="yes")
    o, d = camera[0][:50], camera[1][:50]  # numpy's booleans are booleans (np.True_ was refused)
    np.testing.assert_array_equal(
        bvh.intersect(o, d, nodes_visited=np.True_)["nodes_visited"],
        bvh.intersect(o, d, nodes_visited=True)["nodes_visited"],
    )
