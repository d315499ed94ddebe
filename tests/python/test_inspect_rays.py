"""Bvh.trace_ray and trace_pixel (issue 35): a ray's recorded traversal against what the existing
queries report for it (Bvh.intersect's hit and box-test count; the CPU tracer's cost image for a
pixel), and against the tree's structure."""

import warnings

import numpy as np
import pytest
from oracles import subtree_slots

import bvhlab
from bvhlab.inspect.ray_record import HiddenSurfaceWarning, trace_pixel
from bvhlab.library import procedural, showcase


def _leaf_of_slot(bvh, slot):
    nodes = bvh.nodes
    leaf = np.nonzero(bvh.is_leaf & (nodes["index"] <= slot) & (slot < nodes["index"] + nodes["info"]))[0]
    assert len(leaf) == 1
    return int(leaf[0])


def _check_record(bvh, rec, hit, visited):
    assert rec.box_tests == visited == rec.nodes_visited
    assert (rec.prim, rec.kind) == (hit["prim"], hit["kind"])
    assert rec.t == pytest.approx(hit["t"], rel=0) or (np.isinf(rec.t) and np.isinf(hit["t"]))
    entered = set(rec.box_nodes[rec.box_hit.astype(bool)].tolist())
    for leaf, box_test in zip(rec.prim_leaf, rec.prim_box_test):
        assert leaf in entered and bvh.is_leaf[leaf]
        assert box_test > 0 and leaf in rec.box_nodes[:box_test]  # tested after its box was entered
    if hit["prim"] < 0:
        assert rec.hit_leaf == -1 and not rec.prim_closer.any()
        return
    ref = hit["prim"] | (bvhlab.bvh.REF_SPHERE_BIT if hit["kind"] else 0)
    assert bvh.refs[rec.hit_slot] == ref
    assert rec.hit_leaf == _leaf_of_slot(bvh, rec.hit_slot)  # the leaf holding intersect's primitive
    last = np.nonzero(rec.prim_closer)[0][-1]  # the last primitive that became the closest
    assert (rec.prim_slots[last], rec.prim_leaf[last]) == (rec.hit_slot, rec.hit_leaf)


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_records_match_intersect(traversal, small_scene, knot_mesh):
    for tris, spheres in (small_scene, (knot_mesh, None)):
        bvh = bvhlab.build(tris, spheres, max_leaf_size=4)
        origins, dirs = procedural.random_rays(tris, 300, seed=7)
        hits = bvh.intersect(origins, dirs, traversal=traversal, nodes_visited=True)
        assert (hits["prim"] >= 0).sum() > 50 and (hits["prim"] < 0).sum() > 0, "hits and misses to test"
        for i in range(len(origins)):
            rec = bvh.trace_ray(origins[i], dirs[i], traversal=traversal)
            _check_record(bvh, rec, {k: v[i] for k, v in hits.items()}, hits["nodes_visited"][i])


def _brute_force(bvh, tris, spheres, origin, direction):
    """The closest hit over every primitive, each alone in a tree of its own (no shared tree)."""
    best = (np.inf, -1, 0)
    for kind, prims in ((0, tris), (1, spheres)):
        for p in range(0 if prims is None else len(prims)):
            one = (
                bvhlab.build(prims[p : p + 1])
                if kind == 0
                else bvhlab.build(np.zeros((0, 3, 3), np.float32), prims[p : p + 1])
            )
            t = one.intersect(np.float32([origin]), np.float32([direction]))["t"][0]
            if t < best[0]:
                best = (t, p, kind)
    return best


def test_wide_records_match_intersect_and_brute_force(small_scene, knot_mesh):
    """The wide walk's record: nodes_visited is intersect's (wide nodes visited), every wide node
    after the root was entered as a child box of one visited before it, the hit is intersect's
    and the brute force's, and it ends in the wide leaf (a subtree of at most four) holding it."""
    for tris, spheres in (small_scene, (knot_mesh, None)):
        bvh = bvhlab.build(tris, spheres)
        first, count = subtree_slots(bvh)
        origins, dirs = procedural.random_rays(tris, 300, seed=7)
        hits = bvh.intersect(origins, dirs, traversal="wide", nodes_visited=True)
        for i in range(len(origins)):
            rec = bvh.trace_ray(origins[i], dirs[i], traversal="wide")
            assert rec.nodes_visited == len(rec.wide_nodes) == hits["nodes_visited"][i]
            assert (rec.prim, rec.kind, rec.t) == (hits["prim"][i], hits["kind"][i], hits["t"][i])
            assert rec.wide_nodes[0] == 0 and len(rec.box_wide_step) == rec.box_tests
            for w in range(1, len(rec.wide_nodes)):
                before = rec.box_wide_step < w
                assert rec.wide_nodes[w] in set(rec.box_nodes[before & rec.box_hit.astype(bool)].tolist())
            if rec.prim < 0:
                assert rec.hit_leaf == -1 and not rec.prim_closer.any()
                continue
            leaf = rec.hit_leaf
            assert first[leaf] <= rec.hit_slot < first[leaf] + count[leaf] and count[leaf] <= 4
            last = np.nonzero(rec.prim_closer)[0][-1]
            assert (rec.prim_slots[last], rec.prim_leaf[last]) == (rec.hit_slot, leaf)
            steps = rec.steps()
            assert sum(s["step"] == "wide node" for s in steps) == rec.nodes_visited
        if spheres is not None:  # brute force on a few rays (a tree per primitive is slow)
            for i in range(0, 300, 30):
                t, p, kind = _brute_force(bvh, tris, spheres, origins[i], dirs[i])
                assert (hits["t"][i], hits["prim"][i]) == (t, p) and (p < 0 or hits["kind"][i] == kind)


def test_stack_order_follows_the_tree(knot_mesh):
    bvh = bvhlab.build(knot_mesh)
    origins, dirs = procedural.random_rays(knot_mesh, 50, seed=3)
    nodes, leaf = bvh.nodes, bvh.is_leaf
    for o, d in zip(origins, dirs):
        rec = bvh.trace_ray(o, d, traversal="stack")
        assert rec.box_nodes[0] == 0
        # after the root, boxes come in sibling pairs (first child, second child) of an entered node
        pairs = rec.box_nodes[1:].reshape(-1, 2)
        parents = pairs[:, 0] - 1
        assert not leaf[parents].any()
        np.testing.assert_array_equal(nodes["index"][parents], pairs[:, 1])
        stackless = bvh.trace_ray(o, d, traversal="stackless")
        assert (np.diff(stackless.box_nodes.astype(np.int64)) > 0).all()  # node order, skipping subtrees
        assert (stackless.prim, stackless.hit_leaf) == (rec.prim, rec.hit_leaf)


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_pixel_records_match_the_tracers_cost(traversal):
    scene = showcase.whitted()
    bvh = bvhlab.build(scene, max_leaf_size=2)
    w, h = 48, 32
    options = bvhlab.RenderOptions(traversal=traversal, samples_per_axis=1)
    job = bvhlab.Renderer("cpu").start(scene, bvh, w, h, options=options)
    job.run()
    cost = job.result(color=False, depth=False).cost
    assert len(np.unique(cost)) > 5, "the cost must vary over the picture"
    for y in range(0, h, 3):
        for x in range(0, w, 5):
            rec = trace_pixel(scene, bvh, x, y, width=w, height=h, options=options)
            assert rec.box_tests == cost[y, x], (x, y)
            o, d = np.float32([rec.origin]), np.float32([rec.direction])
            hit = bvh.intersect(o, d, tmin=rec.tmin, tmax=rec.tmax, traversal=traversal, nodes_visited=True)
            _check_record(bvh, rec, {k: v[0] for k, v in hit.items()}, hit["nodes_visited"][0])


def test_pixel_of_several_samples():
    scene = showcase.five_spheres()
    bvh = bvhlab.build(scene)
    options = bvhlab.RenderOptions(samples_per_axis=2)
    job = bvhlab.Renderer("cpu").start(scene, bvh, 24, 16, options=options)
    job.run()
    cost = job.result(color=False, depth=False).cost
    for x, y in ((12, 8), (3, 2), (20, 12)):
        recs = [trace_pixel(scene, bvh, x, y, width=24, height=16, options=options, sample=s) for s in range(4)]
        assert np.mean([r.box_tests for r in recs]) == pytest.approx(cost[y, x], rel=1e-6)
        assert len({r.direction for r in recs}) == 4  # four sample positions


def test_bad_requests_are_refused():
    scene = showcase.five_spheres()
    bvh = bvhlab.build(scene)
    with pytest.raises(ValueError, match="traversal"):
        bvh.trace_ray((0, 0, 0), (1, 0, 0), traversal="bvh2")
    with pytest.raises(ValueError, match="origin"):
        bvh.trace_ray((0, 0), (1, 0, 0))
    with pytest.raises(ValueError):
        bvh.trace_ray((0, 0, 0), (0, 0, 0))  # no direction: the batch query refuses it too
    with pytest.raises(ValueError, match="outside"):
        trace_pixel(scene, bvh, 24, 0, width=24, height=16)
    with pytest.raises(ValueError, match="sample"):
        trace_pixel(scene, bvh, 0, 0, width=24, height=16, sample=1)
    from bvhlab._render_scene import SceneCache

    other = bvhlab.build(scene)  # a render scene of another tree cannot say what this one's rays see
    with pytest.raises(ValueError, match="another version of the tree"):
        bvh._core.trace_ray((0, 0, 0), (1, 0, 0), 0.0, np.inf, "stack", SceneCache().get(scene, other))


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_pixel_records_pass_surfaces_hidden_from_camera_rays_by(traversal):
    """The Whitted scene's spheres hidden from camera rays: the tracer passes them by, and so does the
    pixel's record (before, it walked to the hidden sphere and said so with a warning): its box
    tests, box hits, primitive tests and hits are the tracer's counters at every pixel, where
    the hiding changed them, and its hit is the closest of the triangles alone (a tree without the
    spheres). The wide walk's record still walks to the closest surface, and warns."""
    import dataclasses
    import warnings

    scene = showcase.whitted()
    bvh = bvhlab.build(scene, max_leaf_size=2)
    w, h = 32, 24
    options = bvhlab.RenderOptions(traversal=traversal, samples_per_axis=1, traversal_counters=True)

    def counters():
        job = bvhlab.Renderer("cpu").start(scene, bvh, w, h, options=options)
        job.run()
        return job.result(color=False, depth=False, counters=True).counters

    before = counters()
    spheres_only = set(scene.sphere_material.tolist()) - set(scene.tri_material.tolist())
    assert spheres_only, "materials only the spheres use"
    scene.materials = [
        dataclasses.replace(m, hidden_from=bvhlab.Rays.CAMERA) if k in spheres_only else m
        for k, m in enumerate(scene.materials)
    ]
    after = counters()
    triangles_alone = bvhlab.build(scene.triangles)
    changed = 0
    for x, y in _grid(w, h):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no HiddenSurfaceWarning: the record passes them by
            rec = trace_pixel(scene, bvh, x, y, width=w, height=h, options=options)
        assert _counted(rec) == after[y, x].tolist(), (x, y)
        changed += after[y, x].tolist() != before[y, x].tolist()
        hit = triangles_alone.intersect(np.float32([rec.origin]), np.float32([rec.direction]), tmin=rec.tmin)
        assert (rec.prim, rec.kind) == (hit["prim"][0], 0 if hit["prim"][0] >= 0 else rec.kind), (x, y)
        assert rec.t == hit["t"][0], (x, y)
    assert changed > 10, "the hidden spheres should change the tracer's counters at many pixels"
    wide = dataclasses.replace(options, traversal="wide", traversal_counters=False)
    with pytest.warns(HiddenSurfaceWarning, match="wide walk"):
        trace_pixel(scene, bvh, 16, 12, width=w, height=h, options=wide)


def _counted(rec) -> list:
    """The tracer's five counters of a flat tree's record: box tests, box hits, primitive tests,
    primitives that became the closest hit, instances entered (none)."""
    return [rec.box_tests, rec.box_hits, rec.prim_tests, int(rec.prim_closer.sum()), 0]


def _grid(w: int, h: int):
    return [(x, y) for y in range(0, h, 2) for x in range(0, w, 2)]


def test_pixel_records_and_picks_make_the_render_scene_once(monkeypatch):
    """trace_pixel and the pick's rule for hidden surfaces made a render scene at every call
    (about a second for a million triangles, at every pixel asked and box picked in the Rendered
    viewport): one is kept while the scene, its materials and the tree stay, shared by threads, and
    a pick on a scene where nothing hides makes none."""
    import dataclasses
    from concurrent.futures import ThreadPoolExecutor

    from bvhlab import _render_scene
    from bvhlab.inspect.pick import pick

    made = []
    real = _render_scene._make
    monkeypatch.setattr(_render_scene, "_make", lambda *a: made.append(1) or real(*a))
    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    w, h = 16, 12
    first = [trace_pixel(scene, bvh, x, y, width=w, height=h).summary() for x, y in _grid(w, h)]
    assert len(made) == 1
    origin, direction = np.asarray(first[40]["origin"]), np.asarray(first[40]["direction"])
    plain = pick(bvh, origin, direction)
    assert pick(bvh, origin, direction, scene=scene) == plain and len(made) == 1  # nothing hides: none made
    assert np.isfinite(plain.t_hit)

    hidden = dataclasses.replace(
        scene, materials=[dataclasses.replace(m, hidden_from=bvhlab.Rays.CAMERA) for m in scene.materials]
    )
    with ThreadPoolExecutor(4) as pool:  # two scenes asked in turn by four threads: each answer its scene's
        got = list(pool.map(lambda k: trace_pixel((scene, hidden)[k % 2], bvh, 8, 6, width=w, height=h), range(16)))
    assert all(r.summary() == got[0].summary() for r in got[0::2])
    assert all(r.summary() == got[1].summary() for r in got[1::2])
    assert got[1].prim == -1 and got[0].prim >= 0, "everything hidden: the record passes all by"
    made.clear()
    for _ in range(5):
        assert pick(bvh, origin, direction, scene=hidden).t_hit == np.inf  # every surface passed by
        trace_pixel(hidden, bvh, 3, 4, width=w, height=h)
    assert len(made) <= 1, "the same scene again: the kept render scene"


def test_the_kept_render_scene_goes_with_its_tree():
    """The records' render scene is kept while its tree lives, then dropped with it (review: the
    cache's key held the tree's core, which stayed in memory with its render scene)."""
    import gc

    from bvhlab.inspect import ray_record

    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    trace_pixel(scene, bvh, 3, 4, width=16, height=12)
    kept = ray_record._RENDER_SCENES
    assert kept._owner() is bvh and kept._cache._scene is not None
    del bvh
    gc.collect()
    assert kept._owner is None and kept._cache._scene is None


def test_picks_and_pixel_records_read_one_version_while_another_thread_refits():
    """pick read the boxes and the hit in two calls, and a refit on another thread between them
    (the add-on's viewport worker refits in the background) mixed two trees: 280 of 3,000 picks a
    box without its hit or a leaf never entered; trace_pixel refused 3 of 300 pixels ("the render
    scene is of another version of the tree") while the tree was refit to the same geometry. Both
    now read one version (a snapshot) throughout."""
    import threading

    from bvhlab.inspect.pick import pick
    from bvhlab.inspect.ray_record import trace_pixel

    rng = np.random.default_rng(0)
    near = rng.random((2000, 3, 3), dtype=np.float32)
    near[:, 1:] = near[:, :1] + 0.05 * (near[:, 1:] - 0.5)
    far = near.copy()
    far[..., 0] += 10.0  # the same mesh moved away: the pick ray misses it
    scene = bvhlab.Scene(triangles=near)
    bvh = bvhlab.build(scene)
    c = near[7].mean(0)
    origin, direction = np.array([c[0], c[1], -5.0], np.float32), np.array([0, 0, 1.0], np.float32)

    def refitting(geometries, read):
        """`read()` while another thread refits the tree to each of `geometries` in turn."""
        stop = threading.Event()

        def refits():
            k = 0
            while not stop.is_set():
                bvh.refit(geometries[k % len(geometries)])
                k += 1

        thread = threading.Thread(target=refits)
        thread.start()
        try:
            read()
        finally:
            stop.set()
            thread.join()
        bvh.refit(near)

    seen = set()

    def picks():
        for _ in range(600):
            p = pick(bvh, origin, direction)
            assert (p.how == "box" and np.isfinite(p.t_hit)) or (p.how, p.node) == ("nothing", None), p
            seen.add(p.how)

    def pixels():  # refit to the same geometry: every pixel's record is the render's ray (the
        for _ in range(400):  # old code failed ~1 in 100: 400 pass without the fix 2% of the time)
            assert trace_pixel(scene, bvh, 16, 12, width=32, height=24).t > 0

    refitting([far, near], picks)
    refitting([near], pixels)
    assert seen == {"box", "nothing"}, "the refits never fell between: the case is not met"


def test_a_miss_has_no_kind_in_the_summaries():
    """A ray that hits nothing was summarised as "kind triangle" with prim -1 (the printout, the
    JSON of inspect --pixel; probe)."""
    tris = np.float32([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]])
    bvh = bvhlab.build(tris)
    assert bvh.trace_ray((5, 5, 1), (0, 0, 1)).summary()["kind"] is None
    assert bvh.trace_ray((0.2, 0.2, 1), (0, 0, -1)).summary()["kind"] == "triangle"
    scene = bvhlab.Scene(
        meshes=[tris], instance_mesh=np.array([1]), instance_transforms=np.eye(3, 4, dtype=np.float32)[None]
    )
    instanced = bvhlab.build(scene)
    assert instanced.trace_ray((5, 5, 1), (0, 0, 1)).summary()["kind"] is None


def test_node_figures_take_whole_numbers_only():
    """NodeData.node(True) raised numpy's "truth value of an array is ambiguous", node(1.5) an
    IndexError, and costliest_at_depth(2, 2.7) quietly took 2 (probe): a TypeError naming it."""
    data = bvhlab.build(np.random.default_rng(1).random((50, 3, 3), dtype=np.float32)).node_data()
    for call, words in (
        (lambda: data.node(True), "node must be an integer, got bool"),
        (lambda: data.node(1.5), "node must be an integer, got float"),
        (lambda: data.costliest_at_depth(2, 2.7), "k must be an integer, got float"),
        (lambda: data.worst("3"), "k must be an integer, got str"),
    ):
        with pytest.raises(TypeError, match=words):
            call()
    assert data.node(np.int64(3))["node"] == 3 and len(data.worst(np.int32(3))) == 3


def test_a_pick_ray_float32_cannot_hold_is_refused_as_given():
    """A direction of 1e-50 passed the pick's check and became 0 in float32 (the core then said
    "got 0"); an origin of 1e39 became inf with an overflow warning and "must be finite" (probe)."""
    from bvhlab.inspect.pick import pick

    bvh = bvhlab.build(np.random.default_rng(1).random((50, 3, 3), dtype=np.float32))
    for origin, direction, shown in (((0, 0, 0), (1e-50, 0, 0), r"1e-50"), ((1e39, 0, 0), (1, 0, 0), r"1e\+39")):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(ValueError, match=f"a pick ray needs .* float32 holds, got .*{shown}"):
                pick(bvh, origin, direction)
