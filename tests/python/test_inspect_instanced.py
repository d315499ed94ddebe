"""InstancedBvh.trace_ray and Pick Box's rule on two-level trees (issues 34, 35): a ray's recorded
walk through the TLAS and the instances it entered against InstancedBvh.intersect (hit, instance,
nodes_visited) and against one flat tree over the same triangles moved into the world
(Scene.flattened); the pick against a loop over the boxes the overlay shows; the TLAS's node data
against its boxes and instances."""

import dataclasses

import numpy as np
import pytest
from oracles import box_entry, subtree_slots
from test_instanced_scene import _rays, instanced_scene  # noqa: F401  (the fixture)

import bvhlab
from bvhlab import _render_scene
from bvhlab.inspect.levels import TreeNode, shown_boxes, world_boxes
from bvhlab.inspect.pick import HIT_SLACK, node_world_box, pick_two_level
from bvhlab.library import showcase


@pytest.fixture(scope="module")
def trees(instanced_scene):  # noqa: F811
    tree = bvhlab.build(instanced_scene)
    flat = bvhlab.build(instanced_scene.flattened())
    mesh_of, _ = instanced_scene.instances()
    sizes = [len(instanced_scene.mesh_triangles(int(k))) for k in mesh_of]
    origin_of_flat = (np.repeat(np.arange(len(sizes)), sizes), np.concatenate([np.arange(s) for s in sizes]))
    return tree, flat, origin_of_flat


@pytest.mark.parametrize("traversal", bvhlab.TRAVERSALS)
def test_records_are_intersects_walk_and_the_flattened_trees_hits(instanced_scene, trees, traversal):  # noqa: F811
    tree, flat, (flat_instance, flat_prim) = trees
    mesh_of, _ = tree.instances
    slots = [subtree_slots(m) for m in tree.meshes]
    origins, dirs = _rays(instanced_scene, 300, 5)
    two = tree.intersect(origins, dirs, traversal=traversal, nodes_visited=True)
    one = flat.intersect(origins, dirs, traversal=traversal)
    disagree = hits = 0
    for i in range(len(origins)):
        rec = tree.trace_ray(origins[i], dirs[i], traversal=traversal)
        assert rec.nodes_visited == two["nodes_visited"][i]
        assert rec.nodes_visited == rec.tlas.box_tests + sum(b.nodes_visited for b in rec.blas)
        assert (rec.instance, rec.prim, rec.t) == (two["instance"][i], two["prim"][i], two["t"][i])
        assert len(rec.blas) == len(rec.instances)
        entered_tlas = set(rec.tlas.box_nodes[rec.tlas.box_hit.astype(bool)].tolist())
        assert set(rec.tlas.prim_leaf.tolist()) <= entered_tlas  # instances of entered TLAS leaves
        if rec.prim < 0:
            assert one["prim"][i] < 0 and rec.hit is None and rec.hit_leaf == -1
            continue
        hits += 1
        assert rec.instance in tree.tlas_leaf_instances(rec.hit_tlas_leaf)
        first, count = slots[int(mesh_of[rec.instance])]
        leaf = rec.hit_leaf
        assert first[leaf] <= rec.hit_slot < first[leaf] + count[leaf]  # ends in the leaf holding it
        if traversal != "wide":
            assert tree.meshes[int(mesh_of[rec.instance])].is_leaf[leaf]
        last = rec.hit
        closer = np.nonzero(last.prim_closer)[0][-1]
        assert (last.prim_slots[closer], last.prim_leaf[closer]) == (rec.hit_slot, leaf)
        # the flattened tree's hit: the same instance and primitive, but for rays grazing an edge
        j = one["prim"][i]
        same = j >= 0 and (flat_instance[j], flat_prim[j]) == (rec.instance, rec.prim)
        disagree += not (same and abs(one["t"][i] - rec.t) <= 1e-4 * one["t"][i])
    assert hits > 150 and disagree <= 2, (hits, disagree)


def test_a_scene_of_one_identity_instance_records_no_tlas(small_scene):
    tris, spheres = small_scene
    scene = bvhlab.Scene(
        triangles=tris, spheres=spheres, instance_mesh=[0], instance_transforms=np.eye(3, 4, dtype=np.float32)[None]
    )
    tree = bvhlab.build(scene)
    flat = bvhlab.build(tris, spheres)
    origins, dirs = bvhlab.library.procedural.random_rays(tris, 50, seed=2)
    for o, d in zip(origins, dirs):
        rec = tree.trace_ray(o, d, traversal="wide")
        alone = flat.trace_ray(o, d, traversal="wide")
        assert rec.tlas.box_tests == 0 and len(rec.blas) == 1 and rec.tlas.prim_leaf[0] == 0xFFFFFFFF
        assert rec.nodes_visited == alone.nodes_visited and (rec.prim, rec.t) == (alone.prim, alone.t)
        np.testing.assert_array_equal(rec.blas[0].box_nodes, alone.box_nodes)
        assert rec.hit_tlas_leaf == -1


def test_tlas_node_data_is_its_boxes_and_instances(trees):
    tree, _, _ = trees
    data = tree.tlas_node_data()
    world_lo, world_hi = tree.world_boxes()
    leaves = np.flatnonzero(data.left < 0)
    held = np.concatenate([tree.tlas_leaf_instances(int(n)) for n in leaves])
    assert sorted(held.tolist()) == list(range(len(world_lo)))
    for n in leaves:
        for i in tree.tlas_leaf_instances(int(n)):
            assert tree.tlas_leaf_of(int(i)) == n
            assert np.all(data.lo[n] <= world_lo[i]) and np.all(world_hi[i] <= data.hi[n])
    assert data.prim_count[0] == len(world_lo) and np.isclose(data.sah_cost, tree.stats["tlas_sah_cost"])
    assert data.epo_cost == 0
    lo, hi, depth = tree.tlas_boxes()
    np.testing.assert_array_equal(np.sort(depth), np.sort(data.depth))
    with pytest.raises(ValueError, match="depth_min 3 is greater than depth_max 1"):
        tree.tlas_boxes(3, 1)  # gave no boxes, silently


def _pick_by_brute_force(shown, o, d, t_hit):
    """Of the shown boxes entered no later than t_hit: BLAS before TLAS, the deepest, the first
    entered, the earliest shown; by a loop."""
    best = None
    for k in range(len(shown.lo)):
        t = box_entry(shown.lo[k].astype(float), shown.hi[k].astype(float), o, d)
        if not np.isfinite(t) or t > t_hit * (1 + HIT_SLACK):
            continue
        key = (-int(shown.level[k]), -int(shown.depth[k]), t, k)
        best = key if best is None or key < best else best
    return None if best is None else shown.tree_node(best[3])


@pytest.mark.parametrize("level, depths, leaves_only", [("both", (0, 40), False), ("tlas", (1, 3), False),
                                                        ("blas", (2, 5), False), ("both", (0, 40), True)])  # fmt: skip
def test_pick_is_the_brute_force_pick_over_the_shown_boxes(instanced_scene, trees, level, depths, leaves_only):  # noqa: F811
    tree, _, _ = trees
    shown = shown_boxes(tree, level, *depths, leaves_only=leaves_only)
    origins, dirs = _rays(instanced_scene, 60, 9)
    boxes = 0
    for o, d in zip(origins.astype(np.float64), dirs.astype(np.float64)):
        got = pick_two_level(tree, o, d, level, depths, leaves_only=leaves_only)
        t_hit = tree.intersect(np.float32([o]), np.float32([d]), traversal="stack")["t"][0]
        expected = _pick_by_brute_force(shown, o, d, float(t_hit))
        if expected is not None:
            assert got.box == expected and got.how == "box"
            boxes += 1
        elif np.isfinite(t_hit):
            assert got.how == "hit leaf" and got.box is not None
        else:
            assert got.box is None
    assert boxes >= 10


def test_blas_world_boxes_hold_the_instances_moved_triangles(instanced_scene, trees):  # noqa: F811
    tree, _, _ = trees
    mesh_of, transforms = tree.instances
    for i in range(len(mesh_of)):
        mesh = tree.meshes[int(mesh_of[i])]
        tris = instanced_scene.mesh_triangles(int(mesh_of[i]))
        moved = tris @ transforms[i][:, :3].T + transforms[i][:, 3]
        leaves = np.flatnonzero(mesh.is_leaf)[:20]
        for n in leaves:
            lo, hi = node_world_box(tree, TreeNode("blas", int(n), i))
            start, k = int(mesh.nodes["index"][n]), int(mesh.nodes["info"][n])
            pts = moved[mesh.refs[start : start + k]].reshape(-1, 3)
            assert np.all(lo <= pts.min(0) + 1e-4) and np.all(pts.max(0) <= hi + 1e-4)


def test_a_blas_roots_world_box_is_its_tlas_leafs_box(instanced_scene, trees):  # noqa: F811
    """Stepping from a TLAS leaf to its instance's BLAS root shows the same box (the TLAS's, which
    is tighter than the root box moved by Arvo's method where the instance is rotated), in the
    pick's box and among the overlay's shown boxes; and it holds the instance's moved triangles."""
    tree, _, _ = trees
    mesh_of, transforms = tree.instances
    data = tree.tlas_node_data()
    shown = shown_boxes(tree, "both", 0, 0)
    tighter = 0
    for i in range(len(mesh_of)):
        mesh = tree.meshes[int(mesh_of[i])]
        leaf = tree.tlas_leaf_of(i)
        lo, hi = node_world_box(tree, TreeNode("blas", 0, i))
        np.testing.assert_array_equal(lo, data.lo[leaf])
        np.testing.assert_array_equal(hi, data.hi[leaf])
        k = np.flatnonzero((shown.level == 1) & (shown.instance == i) & (shown.node == 0))
        assert len(k) == 1
        np.testing.assert_array_equal(shown.lo[k[0]], data.lo[leaf])
        np.testing.assert_array_equal(shown.hi[k[0]], data.hi[leaf])
        tris = instanced_scene.mesh_triangles(int(mesh_of[i]))
        pts = (tris @ transforms[i][:, :3].T + transforms[i][:, 3]).reshape(-1, 3)
        assert np.all(lo <= pts.min(0) + 1e-4) and np.all(pts.max(0) <= hi + 1e-4)
        arvo_lo, arvo_hi = world_boxes(mesh.nodes["lo"][:1], mesh.nodes["hi"][:1], transforms[i : i + 1])
        assert np.all(arvo_lo[0, 0] <= lo + 1e-5) and np.all(hi <= arvo_hi[0, 0] + 1e-5)
        tighter += bool(np.any(arvo_lo[0, 0] < lo - 1e-4) or np.any(hi > arvo_hi[0, 0] + 1e-4))
    assert tighter, "the scene has a rotated instance whose moved root box sticks out of its TLAS leaf"


def _counted(rec) -> tuple:
    """The tracer's five counters of a two-level record: box tests, box hits, primitive tests,
    primitives that became the closest hit, instances entered."""
    s = rec.summary()
    closer = sum(int(b.prim_closer.sum()) for b in rec.blas)
    return s["box_tests"], s["box_hits"], s["prim_tests"], closer, s["instances_entered"]


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_pixel_records_of_one_identity_instance_are_the_tracers_counters(traversal):
    """A scene of one mesh placed where it was modelled, as instances (a Blender scene of one
    object): the tracer walks it flat and counts no instance; the record entered it (its one walk
    is recorded) and said 1 instance entered at every pixel. All five counters now agree."""
    from bvhlab.inspect.ray_record import trace_pixel

    flat = showcase.whitted()
    identity = np.eye(3, 4, dtype=np.float32)[None]
    scene = dataclasses.replace(flat, instance_mesh=np.zeros(1, np.int32), instance_transforms=identity)
    tree = bvhlab.build(scene)
    assert isinstance(tree, bvhlab.InstancedBvh)
    w, h = 24, 16
    options = bvhlab.RenderOptions(traversal=traversal, samples_per_axis=1, traversal_counters=True)
    job = bvhlab.Renderer("cpu").start(scene, tree, w, h, options=options)
    job.run()
    counters = job.result(counters=True).counters
    assert (counters[..., 4] == 0).all() and (counters[..., 0] > 0).all()
    hits = 0
    for y in range(h):
        for x in range(w):
            rec = trace_pixel(scene, tree, x, y, width=w, height=h, options=options)
            got = _counted(rec)
            assert got == tuple(counters[y, x].tolist()), (x, y, got, counters[y, x])
            hits += rec.instance == 0
    assert hits > w * h // 4, "the walks are recorded: the hits keep their instance"


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_pixel_records_of_a_two_level_scene_are_the_tracers_counters(instanced_scene, trees, traversal):  # noqa: F811
    """trace_pixel on an instanced scene records the tracer's primary ray through both levels: its
    box tests, box hits, primitive tests, primitive hits and instances entered are the counters
    the CPU tracer keeps for that pixel."""
    from bvhlab.inspect.ray_record import trace_pixel

    tree, _, _ = trees
    w, h = 32, 24
    options = bvhlab.RenderOptions(traversal=traversal, samples_per_axis=1, traversal_counters=True)
    job = bvhlab.Renderer("cpu").start(instanced_scene, tree, w, h, options=options)
    job.run()
    counters = job.result(counters=True).counters
    assert counters[..., 4].max() >= 2, "pixels that enter several instances"
    for y in range(0, h, 2):
        for x in range(0, w, 2):
            rec = trace_pixel(instanced_scene, tree, x, y, width=w, height=h, options=options)
            got = _counted(rec)
            assert got == tuple(counters[y, x].tolist()), (x, y, got, counters[y, x])
            assert rec.nodes_visited == got[0]


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_pixel_records_of_a_two_level_scene_pass_hidden_surfaces_by(instanced_scene, traversal):  # noqa: F811
    """Every third triangle of each mesh made hidden from camera rays (a material of their own):
    the record's BLAS walks pass them by as the tracer does, so its counters are still the
    tracer's at every pixel, and its hit is never a hidden triangle."""
    import dataclasses
    import warnings

    from bvhlab.inspect.ray_record import trace_pixel

    materials = [bvhlab.Material(), bvhlab.Material((1, 0, 0), hidden_from=bvhlab.Rays.CAMERA)]
    hidden_of = [(np.arange(len(instanced_scene.mesh_triangles(k))) % 3 == 0).astype(np.int32) for k in (0, 1)]
    scene = dataclasses.replace(
        instanced_scene, materials=materials, tri_material=hidden_of[0], mesh_tri_material=[hidden_of[1]]
    )
    tree = bvhlab.build(scene)
    w, h = 32, 24
    options = bvhlab.RenderOptions(traversal=traversal, samples_per_axis=1, traversal_counters=True)
    job = bvhlab.Renderer("cpu").start(scene, tree, w, h, options=options)
    job.run()
    counters = job.result(counters=True).counters
    plain = bvhlab.Renderer("cpu").start(instanced_scene, bvhlab.build(instanced_scene), w, h, options=options)
    plain.run()
    assert (plain.result(counters=True).counters != counters).any(axis=-1).sum() > 20, "the hiding changes the walks"
    mesh_of, _ = tree.instances
    hits = 0
    for y in range(h):
        for x in range(w):
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                rec = trace_pixel(scene, tree, x, y, width=w, height=h, options=options)
            got = _counted(rec)
            assert got == tuple(counters[y, x].tolist()), (x, y, got, counters[y, x])
            if rec.instance >= 0:
                hits += 1
                assert not hidden_of[int(mesh_of[rec.instance])][rec.prim], (x, y)
    assert hits > 40, "pixels that hit something"


def test_pixel_records_pass_a_hidden_material_0_of_a_mesh_without_materials_by(instanced_scene):  # noqa: F811
    """Meshes without mesh_tri_material take material 0; hidden from camera rays, the tracer passes
    them by, and so must the record (trace_pixel looked for hidden materials in tri_material and
    mesh_tri_material alone, found none, and walked to them: 36 of 64 pixels differed; review)."""
    import dataclasses

    from bvhlab.inspect.ray_record import trace_pixel

    materials = [bvhlab.Material(hidden_from=bvhlab.Rays.CAMERA), bvhlab.Material((0, 1, 0))]
    visible = np.ones(len(instanced_scene.triangles), np.int32)  # mesh 0 seen (material 1); the knot not
    scene = dataclasses.replace(instanced_scene, materials=materials, tri_material=visible, mesh_tri_material=[])
    tree = bvhlab.build(scene)
    w, h = 24, 18
    options = bvhlab.RenderOptions(traversal="stack", samples_per_axis=1, traversal_counters=True)
    job = bvhlab.Renderer("cpu").start(scene, tree, w, h, options=options)
    job.run()
    counters = job.result(counters=True).counters
    mesh_of, _ = tree.instances
    for y in range(h):
        for x in range(w):
            rec = trace_pixel(scene, tree, x, y, width=w, height=h, options=options)
            got = _counted(rec)
            assert got == tuple(counters[y, x].tolist()), (x, y, got, counters[y, x])
            assert rec.instance < 0 or mesh_of[rec.instance] == 0, (x, y)  # never the hidden knot


def test_cli_inspects_a_pixel_of_an_instanced_scene(instanced_scene, trees, tmp_path, capsys):  # noqa: F811
    """`bvhlab inspect SCENE --pixel X,Y` on a scene file with instances: the pixel's walk through
    both levels, its box tests the CPU tracer's cost there."""
    import json

    from bvhlab.cli import main

    path = instanced_scene.save(tmp_path / "inst.npz")
    w, h = 40, 30
    tree = bvhlab.build(bvhlab.Scene.load(path))
    job = bvhlab.Renderer("cpu").start(instanced_scene, tree, w, h, options=bvhlab.RenderOptions())
    job.run()
    cost = job.result(color=False, depth=False).cost
    y, x = np.unravel_index(np.argmax(cost), cost.shape)
    out = tmp_path / "px.json"
    args = ["inspect", str(path), "--pixel", f"{x},{y}", "--width", str(w), "--height", str(h), "--json", str(out)]
    assert main(args) == 0
    pixel = json.loads(out.read_text())["pixel"]
    assert pixel["box_tests"] == cost[y, x] and pixel["instances_entered"] >= 1
    steps = pixel["steps"]
    assert sum(s["step"] in ("box", "tlas box") for s in steps) == pixel["box_tests"]
    assert sum(s["step"] == "instance" for s in steps) == pixel["instances_entered"]
    table = capsys.readouterr().out
    assert "tlas box" in table and "instances" in table


def test_cli_inspects_nodes_of_both_levels(instanced_scene, trees, tmp_path, capsys):  # noqa: F811
    """--worst K lists TLAS and mesh-tree nodes by the whole tree's SAH under them (the TLAS root
    first, its share 1; each row's cost its own tree's subtree SAH scaled by the instance's area
    weight); --node N [--instance I] prints one of either level; a flat scene refuses --instance,
    a two-level one --save-tree, and a missing instance is a clear error (exit 2)."""
    import json

    from bvhlab.cli import main

    path = instanced_scene.save(tmp_path / "inst.npz")
    tree = bvhlab.build(bvhlab.Scene.load(path))
    data = tree.node_data()
    out = tmp_path / "w.json"
    assert main(["inspect", str(path), "--worst", "12", "--json", str(out)]) == 0
    rows = json.loads(out.read_text())["worst"]
    assert len(rows) == 12 and rows[0]["level"] == "tlas" and rows[0]["node"] == 0
    assert rows[0]["sah_share"] == pytest.approx(1.0)
    assert rows[0]["subtree_sah"] == pytest.approx(tree.stats["sah_cost"])
    costs = [r["subtree_sah"] for r in rows]
    assert costs == sorted(costs, reverse=True)
    blas = [r for r in rows if r["level"] == "blas"]
    assert blas, "the mesh trees' roots cost more than the TLAS's smallest subtrees here"
    for r in blas:
        own = data.meshes[r["mesh"]].subtree_sah[r["node"]]
        assert r["subtree_sah"] == pytest.approx(data.weight[r["instance"]] * own)
    capsys.readouterr()
    i = blas[0]["instance"]
    out = tmp_path / "n.json"
    assert main(["inspect", str(path), "--node", "1", "--instance", str(i), "--json", str(out)]) == 0
    node = json.loads(out.read_text())["node"]
    mesh = data.meshes[int(tree.instances[0][i])]
    assert (node["mesh"], node["prim_count"]) == (int(tree.instances[0][i]), int(mesh.prim_count[1]))
    assert (
        node["depth"]
        == data.tlas.depth[data.leaf_of[i]] + mesh.depth[1]
        == node["depth_in_mesh_tree"] + int(data.tlas.depth[node["tlas_leaf"]])
    )
    assert "mesh tree" in capsys.readouterr().out
    assert main(["inspect", str(path), "--node", "2"]) == 0
    assert "of the TLAS" in capsys.readouterr().out
    bad = {
        ("--node", "0", "--instance", "100000"): "instance 100000 does not exist",
        ("--worst", "2", "--save-tree", str(tmp_path / "t.bvhtree")): "two-level",
        ("--node", "100000"): "node 100000 does not exist",
        ("--worst", "2", "--instance", "7"): "--instance I goes with --node N",  # it was ignored
    }
    for args, said in bad.items():
        assert main(["inspect", str(path), *args]) == 2
        assert said in capsys.readouterr().err
    assert main(["inspect", "gen:whitted", "--node", "0", "--instance", "0"]) == 2
    assert "this scene is flat" in capsys.readouterr().err
    # a flat tree of the scene's own triangles (mesh 0's) loaded against it silently, and every
    # other instance went missing from the hits (probe)
    mesh0 = tmp_path / "mesh0.bvhtree"
    bvhlab.build(bvhlab.Scene.load(path).triangles).save(mesh0)
    assert main(["inspect", str(path), "--worst", "2", "--tree", str(mesh0)]) == 2
    assert "this scene has instances" in capsys.readouterr().err
    with pytest.raises(ValueError, match="this scene has instances"):  # a TreeFileError
        bvhlab.load_bvh(mesh0, bvhlab.Scene.load(path))


def test_pick_with_the_scene_reaches_what_camera_rays_see(instanced_scene):  # noqa: F811
    """pick_two_level with the scene (the Rendered viewport's pick): the knot's material hidden
    from camera rays, each ray reaches the geometry a scene without the knot's instances holds."""
    import dataclasses

    materials = [bvhlab.Material(), bvhlab.Material(hidden_from=bvhlab.Rays.CAMERA)]
    knot = np.ones(len(instanced_scene.meshes[0]), np.int32)
    scene = dataclasses.replace(instanced_scene, materials=materials, mesh_tri_material=[knot])
    tree = bvhlab.build(scene)
    mesh_of, transforms = instanced_scene.instances()
    cloud_only = dataclasses.replace(
        instanced_scene, instance_mesh=mesh_of[mesh_of == 0], instance_transforms=transforms[mesh_of == 0]
    )
    expected = bvhlab.build(cloud_only)
    origins, dirs = _rays(instanced_scene, 200, 9)
    want = expected.intersect(origins, dirs, traversal="stack")["t"]
    differ = 0
    made = []
    real = _render_scene._make
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(_render_scene, "_make", lambda *a: made.append(1) or real(*a))
        for i in range(len(origins)):
            seen = pick_two_level(tree, origins[i], dirs[i], scene=scene)
            drawn = pick_two_level(tree, origins[i], dirs[i])
            assert seen.t_hit == want[i] or (np.isinf(seen.t_hit) and np.isinf(want[i])), i
            differ += seen.t_hit != drawn.t_hit
    assert differ > 20, "rays that reach the hidden knot"
    # one render scene for the 200 picks (review: each pick's snapshot of the tree made its own)
    assert len(made) <= 1
