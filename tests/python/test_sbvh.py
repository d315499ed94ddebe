"""method="sbvh" (spatial splits, Stich, Friedrich and Dietrich 2009): a valid tree whose leaves
hold clipped parts of their triangles, references that repeat within the budget, the same hits as
brute force and as the binned tree, one tree for every thread count, and everything that reads a
tree (stats, views, wide tree, occluded, refit, save/load, the CPU tracer) with repeated references."""

import numpy as np
import pytest
from oracles import brute_force

import bvhlab
from bvhlab.library import procedural


@pytest.fixture(scope="module")
def long_triangles():
    """Long thin triangles across a room and small ones: a scene where spatial splits pay."""
    rng = np.random.default_rng(7)
    small = procedural.random_triangles(1500, size=0.05, seed=4)
    a = rng.uniform(0, 1, (300, 3)).astype(np.float32)
    b = rng.uniform(0, 1, (300, 3)).astype(np.float32)
    long = np.stack([a, b, b + rng.normal(0, 0.02, (300, 3)).astype(np.float32)], axis=1)
    return np.ascontiguousarray(np.concatenate([small, long]).astype(np.float32))


def sbvh(tris, spheres=None, **kw):
    return bvhlab.build(tris, spheres, method="sbvh", **kw)


def sample_points(tris, k=6):
    """Points spread over each triangle (vertices, edges and inside): (T, S, 3) float64."""
    u, v = np.meshgrid(np.linspace(0, 1, k), np.linspace(0, 1, k))
    keep = u + v <= 1
    u, v = u[keep], v[keep]
    t = tris.astype(np.float64)
    return (
        t[:, None, 0] * (1 - u - v)[None, :, None] + t[:, None, 1] * u[None, :, None] + t[:, None, 2] * v[None, :, None]
    )


def check_sbvh_tree(bvh, tris, spheres=None):
    """Layout, skip links and depths; every primitive in some leaf, never twice in one leaf; every
    box inside its parent's; and every point of every triangle inside the box of a leaf that holds
    it (the leaves' boxes hold the triangles' clipped parts, together the whole triangle)."""
    spheres = np.zeros((0, 4), np.float32) if spheres is None else spheres
    nodes, refs, depths, leaf, skip = bvh.nodes, bvh.refs, bvh.depths, bvh.is_leaf, bvh.skip
    n_prims = len(tris) + len(spheres)
    internal = np.flatnonzero(~leaf)
    second = nodes["index"][internal]
    assert np.array_equal(second, skip[internal + 1]), "second child follows the first's subtree"
    assert np.array_equal(skip[internal], skip[second])
    assert np.all(skip[leaf] == np.flatnonzero(leaf) + 1) and skip[0] == len(nodes)
    assert np.all(depths[internal + 1] == depths[internal] + 1) and np.all(depths[second] == depths[internal] + 1)
    for child in (internal + 1, second):
        assert np.all(nodes["lo"][child] >= nodes["lo"][internal]) and np.all(
            nodes["hi"][child] <= nodes["hi"][internal]
        )
    leaves = nodes[leaf]
    slots = np.concatenate([np.arange(n["index"], n["index"] + n["info"]) for n in leaves])
    assert np.array_equal(np.sort(slots), np.arange(len(refs))), "every slot in exactly one leaf"
    assert len(refs) <= bvhlab._core.sbvh_reference_limit(n_prims, bvh.config.core())
    is_sphere = (refs & bvhlab.bvh.REF_SPHERE_BIT) != 0
    key = np.where(is_sphere, len(tris) + (refs & ~np.uint32(bvhlab.bvh.REF_SPHERE_BIT)), refs).astype(np.int64)
    assert np.array_equal(np.unique(key), np.arange(n_prims)), "every primitive reachable"
    leaf_of_slot = np.empty(len(refs), np.int64)
    leaf_of_slot[slots] = np.repeat(np.arange(len(leaves)), leaves["info"].astype(np.int64))
    assert len(np.unique(leaf_of_slot * (n_prims + 1) + key)) == len(refs), "no primitive twice in one leaf"
    lo, hi = leaves["lo"][leaf_of_slot].astype(np.float64), leaves["hi"][leaf_of_slot].astype(np.float64)
    # spheres: a leaf's box meets the sphere's box (spheres are cut as boxes)
    c, r = spheres[key[is_sphere] - len(tris), :3], spheres[key[is_sphere] - len(tris), 3:]
    assert np.all((c - r <= hi[is_sphere]) & (c + r >= lo[is_sphere]))
    # triangles: each sample point lies in at least one of its leaves' boxes
    tri = ~is_sphere
    points = sample_points(tris)
    covered = np.zeros(points.shape[:2], bool)
    inside = np.all((points[key[tri]] >= lo[tri, None]) & (points[key[tri]] <= hi[tri, None]), axis=2)
    np.logical_or.at(covered, key[tri], inside)
    assert covered.all(), f"{(~covered).sum()} triangle points outside every leaf that holds them"
    s = bvh.stats
    assert s["references"] == len(refs) and s["primitives"] == n_prims
    assert s["nodes"] == len(nodes) == 2 * s["leaves"] - 1
    assert sum(k * c for k, c in enumerate(s["leaf_size_histogram"])) == len(refs)
    assert s["height"] == depths.max() + 1 <= 64


def test_valid_tree_with_repeated_references(long_triangles):
    bvh = sbvh(long_triangles, max_leaf_size=2)
    assert bvh.stats["references"] > len(long_triangles), "the scene must make spatial splits to test them"
    check_sbvh_tree(bvh, long_triangles)
    assert bvh.stats["sah_cost"] < bvhlab.build(long_triangles, max_leaf_size=2).stats["sah_cost"]


def test_valid_with_spheres_and_every_leaf_size(small_scene):
    tris, spheres = small_scene
    for leaf in (1, 4):
        check_sbvh_tree(sbvh(tris, spheres, max_leaf_size=leaf), tris, spheres)
    check_sbvh_tree(sbvh(tris, spheres, sbvh_unsplit=False, bins=32), tris, spheres)


@pytest.mark.parametrize("budget", [1.0, 1.05, 1.5, 3.0])
def test_budget_respected(long_triangles, budget):
    bvh = sbvh(long_triangles, sbvh_budget=budget)
    assert len(bvh.refs) <= int(np.floor(np.float32(budget) * np.float64(len(long_triangles))))
    if budget == 1.0:
        assert len(bvh.refs) == len(long_triangles)  # object splits only
    check_sbvh_tree(bvh, long_triangles)


def test_alpha_limits_spatial_splits(long_triangles):
    refs = [len(sbvh(long_triangles, sbvh_alpha=a).refs) for a in (0.0, 1e-5, 1e-2, 1e3)]
    # (a node whose centroids all coincide may still split spatially: it has no object split)
    assert refs[0] >= refs[1] >= refs[2] >= refs[3] and refs[3] < refs[1]


def test_hits_equal_brute_force_and_the_binned_tree(long_triangles, small_scene):
    for tris, spheres in ((long_triangles, None), small_scene):
        o, d = procedural.random_rays(tris, 3000, seed=9)
        d[::7, 1] = 0  # axis-parallel components
        binned = bvhlab.build(tris, spheres).intersect(o, d)
        want_t, want_id, _ = brute_force(tris, np.zeros((0, 4), np.float32) if spheres is None else spheres, o, d)
        assert np.isfinite(want_t).mean() > 0.2
        for leaf in (1, 4):
            bvh = sbvh(tris, spheres, max_leaf_size=leaf)
            for traversal in bvhlab.TRAVERSALS:
                got = bvh.intersect(o, d, traversal=traversal)
                for k in ("t", "prim", "kind", "u", "v"):
                    np.testing.assert_array_equal(got[k], binned[k], err_msg=f"{traversal} {k}")
                blocked = bvh.occluded(o, d, tmax=np.float32(0.5), traversal=traversal)
                np.testing.assert_array_equal(blocked, got["t"] < np.float32(0.5))
            hit = np.isfinite(want_t)
            assert np.array_equal(np.isfinite(got["t"]), hit)
            np.testing.assert_allclose(got["t"][hit], want_t[hit], rtol=1e-4, atol=1e-6)


def test_same_tree_on_every_thread_count(long_triangles):
    trees = [sbvh(long_triangles, threads=t) for t in (1, 2, 4)]
    for t in trees[1:]:
        assert t.nodes.tobytes() == trees[0].nodes.tobytes() and np.array_equal(t.refs, trees[0].refs)


@pytest.mark.parametrize(
    ("setting", "value", "error"),
    [
        ("sbvh_alpha", -1e-5, ValueError),
        ("sbvh_alpha", float("nan"), ValueError),
        ("sbvh_alpha", float("inf"), ValueError),
        ("sbvh_budget", 0.5, ValueError),
        ("sbvh_budget", 0.0, ValueError),
        ("sbvh_budget", float("nan"), ValueError),
        ("sbvh_budget", 1e9, ValueError),
        ("sbvh_alpha", "small", TypeError),
        ("sbvh_unsplit", 1, TypeError),
    ],
)
def test_hostile_settings(setting, value, error):
    tris = procedural.random_triangles(50, seed=1)
    with pytest.raises(error, match=setting):
        sbvh(tris, **{setting: value})
    with pytest.raises(error, match=setting):
        bvhlab.BuildConfig(method="sbvh", **{setting: value})


def test_refit_rebuilds(long_triangles):
    """A refit of an SBVH is a rebuild over the moved geometry (its clipped boxes cannot be refitted)."""
    bvh = sbvh(long_triangles)
    moved = np.ascontiguousarray(long_triangles * np.float32(1.5) + np.float32(0.25))
    moved[:40] += np.float32(0.3)
    bvh.refit(moved)
    fresh = sbvh(moved)
    assert bvh.nodes.tobytes() == fresh.nodes.tobytes() and np.array_equal(bvh.refs, fresh.refs)
    check_sbvh_tree(bvh, moved)
    o, d = procedural.random_rays(moved, 1000, seed=3)
    want_t, want_id, _ = brute_force(moved, np.zeros((0, 4), np.float32), o, d)
    got = bvh.intersect(o, d)
    assert np.array_equal(np.isfinite(got["t"]), np.isfinite(want_t))
    for policy in bvhlab.UPDATE_POLICIES:
        tree = sbvh(long_triangles)
        stats = tree.update(moved, policy=policy)
        assert stats.policy == "rebuild" and tree.nodes.tobytes() == fresh.nodes.tobytes()


def test_save_load_and_optimize(long_triangles, tmp_path):
    bvh = sbvh(long_triangles)
    bvh.save(tmp_path / "t.bvhtree")
    back = bvhlab.load_bvh(tmp_path / "t.bvhtree", long_triangles)
    assert back.nodes.tobytes() == bvh.nodes.tobytes() and np.array_equal(back.refs, bvh.refs)
    assert back.config == bvh.config and back.stats["references"] == len(bvh.refs)
    o, d = procedural.random_rays(long_triangles, 1000, seed=4)
    want = bvh.intersect(o, d)
    np.testing.assert_array_equal(back.intersect(o, d)["prim"], want["prim"])
    bvh.optimize(iterations=5)
    check_sbvh_tree(bvh, long_triangles)
    np.testing.assert_array_equal(bvh.intersect(o, d)["t"], want["t"])


def test_cpu_tracer_and_overlay_with_repeated_references(long_triangles):
    scene = bvhlab.Scene(triangles=long_triangles, spheres=procedural.random_spheres(20, radius=0.05, seed=1))
    binned = bvhlab.build(scene)
    spatial = bvhlab.build(scene, method="sbvh")
    assert spatial.stats["references"] > spatial.stats["primitives"]
    a, _ = bvhlab.render(scene, binned, 64, 48, backend="cpu")
    b, _ = bvhlab.render(scene, spatial, 64, 48, backend="cpu")
    np.testing.assert_array_equal(a, b)
    lo, hi, depth = spatial.boxes()
    assert len(lo) == len(spatial.nodes) and np.all(lo <= hi)


@pytest.fixture(scope="module")
def floor_under_clutter():
    """Two triangles of a 10 × 10 floor under 3,000 small ones: the floor's triangles are cut into
    many parts, in columns of parts sharing their planes."""
    floor = np.array([[(0, 0, 0), (10, 0, 0), (10, 10, 0)], [(0, 0, 0), (10, 10, 0), (0, 10, 0)]], np.float32)
    clutter = procedural.random_triangles(3000, size=0.05, seed=5) * np.float32([10, 10, 0.3])
    return np.ascontiguousarray(np.concatenate([floor, clutter]).astype(np.float32))


@pytest.mark.parametrize("scene", ["long_triangles", "floor_under_clutter"])
def test_a_leaf_box_shrunk_off_part_of_a_triangle_is_refused_on_load(scene, request, tmp_path):
    """A saved SBVH whose leaf box no longer holds all of a triangle's part (the box shrunk along
    its longest axis, still meeting each of its primitives' boxes, the file's checksum made to fit):
    it loaded (an SBVH leaf's box need only meet its primitives'), and rays through the part it
    dropped missed the triangle. The leaves' boxes of each primitive must cover all of it. On the
    floor, a triangle in many parts (the check once followed pieces of no area, doubling them at
    each part of a column, and gave up)."""
    from test_tree_file import _rewrite

    tris = request.getfixturevalue(scene)
    bvh = sbvh(tris)
    path = tmp_path / "t.bvhtree"
    bvh.save(path)
    nodes, refs = bvh.nodes, bvh.refs
    leaves = np.flatnonzero(bvh.is_leaf)
    slots = {leaf: refs[nodes["index"][leaf] : nodes["index"][leaf] + nodes["info"][leaf]] for leaf in leaves}
    corner_lo, corner_hi = tris.min(axis=1), tris.max(axis=1)
    candidates = range(len(tris)) if scene == "long_triangles" else (0, 1)
    if scene == "floor_under_clutter":
        assert min(np.count_nonzero(refs == t) for t in candidates) >= 20, "the floor in many parts"

    def lost_part(leaf, shrunk, tri) -> bool:
        """Whether sample points of `tri` are held by none of its leaves' boxes, `leaf`'s shrunk."""
        p = sample_points(tris[tri : tri + 1], k=9 if scene == "long_triangles" else 300)[0]
        covered = np.zeros(len(p), bool)
        for other, held in slots.items():
            if tri in held:
                hi = shrunk if other == leaf else nodes["hi"][other]
                covered |= np.all((p >= nodes["lo"][other]) & (p <= hi), axis=1)
        return not covered.all()

    for leaf in (leaf for leaf in leaves if any(t in candidates for t in slots[leaf])):
        lo, hi = nodes["lo"][leaf].copy(), nodes["hi"][leaf].copy()
        held = slots[leaf]
        axis = int(np.argmax(hi - lo))
        shrunk = hi.copy()
        shrunk[axis] = max(lo[axis], float(corner_lo[held, axis].max()))
        if shrunk[axis] > hi[axis] - 0.2 * (hi[axis] - lo[axis]):
            continue
        if any(lost_part(leaf, shrunk, t) for t in held if t in candidates):
            break
    else:
        pytest.fail("no leaf whose shrinking uncovers a triangle")
    assert np.all(shrunk >= corner_lo[held].min(axis=0)) and np.all(lo <= corner_hi[held].max(axis=0))
    bvhlab.load_bvh(path, tris)  # as saved: it loads

    def change(saved_nodes):
        saved_nodes["hi"][leaf] = shrunk

    _rewrite(path, change)
    with pytest.raises(ValueError, match="is not covered by its leaves' boxes"):
        bvhlab.load_bvh(path, tris)


def test_every_saved_sbvh_loads(long_triangles, small_scene, floor_under_clutter, tmp_path):
    """The coverage check refuses no tree the builder makes: triangles and spheres, every leaf
    size, α and budget, optimised, a floor in many parts."""
    tris, spheres = small_scene
    for k, (geometry, settings) in enumerate(
        [
            ((floor_under_clutter, None), {}),
            ((long_triangles, None), {}),
            ((long_triangles, None), {"max_leaf_size": 1}),
            ((long_triangles, None), {"sbvh_alpha": 0.0, "max_leaf_size": 8}),
            ((tris, spheres), {"max_leaf_size": 2}),
            ((tris, spheres), {"sbvh_alpha": 1e-9}),
        ]
    ):
        bvh = sbvh(*geometry, **settings)
        if k == 2:
            bvh.optimize(iterations=5)
        bvh.save(tmp_path / f"{k}.bvhtree")
        back = bvhlab.load_bvh(tmp_path / f"{k}.bvhtree", *geometry)
        assert back.nodes.tobytes() == bvh.nodes.tobytes()
