"""The add-on on an instanced scene (issue 34), under bpy 4.2: the sidebar's Build, F12, the
Rendered viewport, Compare and Export stats share one two-level tree (counted builds); the
overlay's TLAS and BLAS boxes against the BLAS node boxes moved here by each instance's matrix
(corners transformed, not Arvo's extents as the add-on does); the viewport's image against
bvhlab.render of the flattened scene over a flat tree; moving an instance makes a new TLAS and
nothing else, editing the shared mesh updates its tree alone with the chosen policy."""

import csv
import json
from importlib import import_module

import blender_checks  # noqa: F401  (import path for the shared checks)
import bpy  # noqa: E402  (after harness)
import checks_engine  # noqa: E402
import checks_engine_viewport as viewport_checks  # noqa: E402
import harness  # before bpy
import numpy as np
import pytest
from blender_instance_scenes import PLACES  # noqa: E402  (rotation, non-uniform scale, a mirror)

import bvhlab  # noqa: E402
import bvhlab.blender  # noqa: E402


@pytest.fixture(scope="module", autouse=True)
def addon_enabled():
    harness.enable_addon_from_source()


def _addon(name: str):
    return import_module(f"{harness.addon().__name__}.{name}")


def instanced_scene(resolution=(48, 36)):
    """Suzanne (968 triangles) in a collection instanced by four empties (PLACES), and a box used
    once (mesh 0, in the world)."""
    scene = harness.empty_scene(resolution)
    harness.add_camera((0.5, -12.0, 5.0), (0.0, 0.5, 0.0), lens=30)
    harness.add_point_light((3.0, -5.0, 6.0))
    source = bpy.data.collections.new("Source")
    bpy.ops.mesh.primitive_monkey_add()
    monkey = bpy.context.active_object
    monkey.name = monkey.data.name = "Monkey"
    bpy.context.scene.collection.objects.unlink(monkey)
    source.objects.link(monkey)
    for i, (location, rotation, scale) in enumerate(PLACES):
        empty = bpy.data.objects.new(f"Instance {i}", None)
        empty.instance_type, empty.instance_collection = "COLLECTION", source
        bpy.context.scene.collection.objects.link(empty)
        empty.location, empty.rotation_euler, empty.scale = location, rotation, scale
    harness.add_box("Floor box", (0.0, 0.0, -2.0), size=1.5, scale=(4.0, 4.0, 0.3))
    bpy.context.view_layer.update()
    return scene


def test_build_then_f12_render_and_export_share_one_two_level_tree(tmp_path):
    """Build makes the two-level tree (one build, its stats stored against flattened); F12, the
    sidebar's Render and Export stats then use it as it is (no second build); Export stats writes
    the TLAS and every BLAS."""
    scene = instanced_scene()
    counts = _addon("trees").counts
    builds = counts.snapshot()[0]
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    assert counts.snapshot()[0] == builds + 1
    built = harness.addon().state.tree_for(scene)
    assert isinstance(built.bvh, bvhlab.InstancedBvh), "the sidebar flattened the instanced scene"
    s = built.bvh.stats
    exported = bvhlab.blender.export_scene(bpy.context)
    flat = exported.flattened()
    assert (s["instances"], s["meshes"]) == (5, 2)  # mesh 0 once, Suzanne four times
    assert s["triangles"] == len(exported.triangles) + len(exported.meshes[0]) == 12 + 968
    assert s["triangles_flattened"] == len(flat.triangles) == 12 + 4 * 968
    checks_engine.use_engine(scene, backend="cpu", render_supersampling=1, render_overlay=False)
    checks_engine.render_passes(tmp_path)
    assert checks_engine._last_final(scene)["tree"] == "kept"
    assert bpy.ops.bvhlab.render() == {"FINISHED"}
    path = tmp_path / "stats.json"
    assert bpy.ops.bvhlab.export_stats(filepath=str(path)) == {"FINISHED"}
    assert counts.snapshot()[0] == builds + 1, "F12, Render or Export stats built the tree again"
    assert harness.addon().state.tree_for(scene).bvh is built.bvh
    written = json.loads(path.read_text())["stats"]
    assert written["instances"] == 5 and written["mesh_instances"] == [1, 4]
    assert written["mesh_sah_cost"] == [m.stats["sah_cost"] for m in built.bvh.meshes]
    rows = list(csv.reader(path.with_suffix(".csv").open()))
    assert ["mesh_primitives", "1", "968"] in rows


def test_f12_traces_the_boxes_of_the_overlay_level(tmp_path):
    """F12 with the boxes in the image follows the panel's Level: "blas" traces the BLAS boxes moved
    into the world, the image bvhlab.render gives with overlay_level "blas" (CPU reference: equal)
    and not the TLAS's (tests/python/test_render_instanced.py checks the pixels of a BLAS edge)."""
    scene = instanced_scene()
    checks_engine.use_engine(
        scene, backend="cpu", render_supersampling=1, render_overlay=True, overlay_depth_min=1, overlay_depth_max=2
    )
    images = {}
    for level in ("blas", "tlas"):
        scene.bvhlab.overlay_level = level
        got = checks_engine.render_passes(tmp_path, level)["Combined"]
        record = checks_engine._last_final(scene)
        options = scene.bvhlab.render_options()
        assert options.overlay_level == level and options.overlay_depth == (1, 2)
        width, height = scene.render.resolution_x, scene.render.resolution_y
        want, _ = bvhlab.render(
            record["scene"],
            bvhlab.build(record["scene"], config=scene.bvhlab.build_config()),
            width,
            height,
            backend="cpu",
            options=options,
        )
        checks_engine.compare_images(got, want, "cpu")
        images[level] = got
    assert np.abs(images["blas"] - images["tlas"]).max(-1).astype(bool).mean() > 0.01


def _corner_boxes(lo: np.ndarray, hi: np.ndarray, transform: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World boxes of object-space boxes: the eight corners of each moved, then their min and max."""
    corners = np.stack([np.where([(c >> a) & 1 for a in range(3)], hi, lo) for c in range(8)], 1)  # (B,8,3)
    world = corners.astype(np.float64) @ transform[:, :3].T.astype(np.float64) + transform[:, 3]
    return world.min(1), world.max(1)


def _sorted_rows(lo, hi, depth) -> np.ndarray:
    rows = np.concatenate([np.asarray(depth, np.float64)[:, None], lo, hi], 1)
    return rows[np.lexsort(rows.T[::-1])]


def _expected_blas_boxes(bvh, depth_min, depth_max, instances=None):
    """The BLAS node boxes in the depth range of each instance's mesh (from the nodes and depths
    arrays), moved by its matrix."""
    mesh_of, transforms = bvh.instances
    parts = []
    for i in range(len(mesh_of) if instances is None else instances):
        mesh = bvh.meshes[int(mesh_of[i])]
        keep = (mesh.depths >= depth_min) & (mesh.depths <= depth_max)
        lo, hi = _corner_boxes(mesh.nodes["lo"][keep], mesh.nodes["hi"][keep], transforms[i])
        parts.append((lo, hi, mesh.depths[keep]))
    return tuple(np.concatenate([p[k] for p in parts]) for k in range(3))


def test_overlay_boxes_are_the_blas_boxes_moved_by_each_instance_and_the_tlas_boxes():
    """BLAS boxes: every instance's mesh tree's node boxes in the depth range, moved into the world
    (a mirrored and a non-uniformly scaled instance among them); TLAS boxes: its leaves are the
    instances' world boxes, each inside the root; both: the two together; a cap keeps the first
    instances whose boxes fit and says so."""
    instanced_scene()
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    bvh = harness.addon().state.tree_for(bpy.context.scene).bvh
    levels = _addon("overlay.levels")
    depth_min, depth_max = 1, 4
    got = levels.two_level_boxes(bvh, "blas", depth_min, depth_max)
    expected = _expected_blas_boxes(bvh, depth_min, depth_max)
    assert len(got.lo) == len(expected[0]) > 5 * 4 and got.note == ""
    assert np.all(np.diff(got.depth.astype(int)) >= 0), "not sorted by depth"
    scale = np.abs(expected[1]).max()
    np.testing.assert_allclose(_sorted_rows(got.lo, got.hi, got.depth), _sorted_rows(*expected), atol=1e-5 * scale)

    tlas = levels.two_level_boxes(bvh, "tlas", 0, 63, leaves_only=True)
    world_lo, world_hi = bvh.world_boxes()
    assert np.array_equal(
        _sorted_rows(tlas.lo, tlas.hi, 0 * tlas.depth), _sorted_rows(world_lo, world_hi, 0 * tlas.depth)
    )
    root = levels.two_level_boxes(bvh, "tlas", 0, 0)
    assert len(root.lo) == 1 and np.all(root.lo[0] <= world_lo) and np.all(root.hi[0] >= world_hi)

    both = levels.two_level_boxes(bvh, "both", depth_min, depth_max)
    tlas_part = levels.two_level_boxes(bvh, "tlas", depth_min, depth_max)
    assert len(both.lo) == len(got.lo) + len(tlas_part.lo)

    per_instance = [
        int(((m.depths >= 1) & (m.depths <= 4)).sum()) for m in (bvh.meshes[int(k)] for k in bvh.instances[0])
    ]
    cap = per_instance[0] + per_instance[1] + per_instance[2] // 2
    capped = levels.two_level_boxes(bvh, "blas", depth_min, depth_max, cap=cap)
    assert capped.instances_shown == 2 and len(capped.lo) <= cap and "2 of 5 instances" in capped.note
    np.testing.assert_allclose(
        _sorted_rows(capped.lo, capped.hi, capped.depth),
        _sorted_rows(*_expected_blas_boxes(bvh, depth_min, depth_max, instances=2)),
        atol=1e-5 * scale,
    )
    table = _addon("overlay.batch").BoxTable.from_boxes(got.lo, got.hi, got.depth)
    first, count = table.depth_slice(2, 3)
    assert count == int(((got.depth >= 2) & (got.depth <= 3)).sum())
    assert np.all((table.rows[first : first + count, 3] >= 2) & (table.rows[first : first + count, 3] <= 3))


def _frame_after(session, previous):
    """The first full-resolution frame after `previous`."""
    return viewport_checks._wait(
        lambda: f if (f := session.latest_frame()) is not None and f is not previous and f.level == "full" else None
    )


def _flat_render(scene_export, request):
    flat = scene_export.flattened()
    image, _ = bvhlab.render(
        flat,
        bvhlab.build(flat),
        request.frustum.width,
        request.frustum.height,
        backend="cpu",
        camera=request.frustum.camera(),
        max_depth=5,
        traversal="stackless",
    )
    return image


def _resync(session, live, change):
    """`change()`, then what view_update does after it: sync the LiveScene with the depsgraph's
    updates (listed only inside Blender's update handlers, as inside view_update)."""
    reports = []

    def synced(scene, depsgraph):
        reports.append(live.sync(depsgraph, scene, bpy.context.view_layer))

    bpy.app.handlers.depsgraph_update_post.append(synced)
    try:
        change()
        bpy.context.view_layer.update()
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(synced)
    session.set_scene(live.scene, reports[-1])
    return reports[-1]


def test_rendered_viewport_traces_the_two_level_tree_and_moves_only_the_tlas():
    """The viewport's worker on the instanced scene: a two-level tree, its image the flattened
    scene's (flat tree, CPU reference: within float rounding of the two-level walk); moving an
    instancer changes the image and makes one new TLAS (no mesh tree built or updated); editing
    the shared mesh updates its tree alone, with the policy asked for (refit here)."""
    scene = instanced_scene()
    counts = _addon("trees").counts
    session, request, live = viewport_checks._session_for(scene, 64, 48, samples_per_axis=1)
    try:
        frame = _frame_after(session, None)
        tree = viewport_checks._tree_of(request)
        assert isinstance(tree.bvh, bvhlab.InstancedBvh) and frame.timings["tree"] == "built"
        _same_image(frame.image, _flat_render(live.scene, request))

        before = counts.snapshot()
        assert _resync(session, live, lambda: _move(bpy.data.objects["Instance 1"], 1.5)).placeable
        moved = _frame_after(session, frame)
        assert moved.timings["tree"] == "placed", moved.timings["tree"]
        builds, mesh_builds, mesh_updates, tlas_builds = counts.snapshot()
        assert (builds, mesh_builds, mesh_updates) == before[:3] and tlas_builds == before[3] + 1
        assert np.abs(moved.image - frame.image).max() > 0.1, "the moved instance is not in the image"
        _same_image(moved.image, _flat_render(live.scene, request))

        policy_request = viewport_checks._engine_module("viewport").ViewRequest(
            request.frustum, request.settings, "cpu", request.tree, 5.0, update=bvhlab.UpdateConfig(policy="refit")
        )
        session.request(policy_request)
        moved = _frame_after(session, moved)  # the same scene traced for the new request
        before = counts.snapshot()
        assert _resync(session, live, _edit_monkey).refittable
        edited = _frame_after(session, moved)
        assert tree.last.action == "refit" and tree.last.policy == "refit", tree.last
        builds, mesh_builds, mesh_updates, tlas_builds = counts.snapshot()
        assert (builds, mesh_builds) == before[:2] and mesh_updates == before[2] + 1 and tlas_builds == before[3] + 1
        _same_image(edited.image, _flat_render(live.scene, policy_request))
    finally:
        session.close()


def _move(obj, dx: float) -> None:
    obj.location.x += dx


def _edit_monkey() -> None:
    mesh = bpy.data.meshes["Monkey"]
    mesh.vertices[0].co.z += 0.3
    mesh.update()


def _same_image(got: np.ndarray, flat: np.ndarray) -> None:
    """The two-level walk against the flat tree: the same hits within float rounding (rays moved
    into an instance's space), so nearly every pixel equal."""
    diff = np.abs(got - flat).max(-1)
    assert (diff > 1e-3).mean() <= 0.01, f"{(diff > 1e-3).mean():.4f} of the pixels differ"


def test_fresh_sah_is_measured_on_demand_against_the_updated_tree():
    """Right after a build the tree is a fresh build (the same SAH cost); after a refit of a large
    deformation the fresh build's cost is below the refit tree's. The panel's button runs it."""
    scene = instanced_scene()
    scene.bvhlab.update_policy = "refit"
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    built = harness.addon().state.tree_for(scene)
    assert built.tree.known_fresh_sah_cost() is None
    assert bpy.ops.bvhlab.fresh_sah() == {"FINISHED"}
    assert built.tree.known_fresh_sah_cost() == pytest.approx(built.bvh.stats["sah_cost"], rel=1e-6)
    exported = bvhlab.blender.export_scene(bpy.context)
    rng = np.random.default_rng(3)
    monkey = exported.meshes[0].copy()
    monkey[rng.permutation(len(monkey))[: len(monkey) // 2]] *= 3.0  # half of the triangles far out
    exported.meshes = [monkey]
    update = built.tree.update(exported, refittable=True, policy=bvhlab.UpdateConfig(policy="refit"))
    assert update.action == "refit" and update.meshes_updated == 1 and update.meshes_built == 0
    assert built.tree.fresh_sah_cost() < 0.95 * built.bvh.stats["sah_cost"]


def test_compare_reports_the_tlas_and_the_meshes_trees(tmp_path):
    """Compare on the instanced scene builds and renders every method two-level: its rows and CSV
    hold the TLAS's figures, the stored and flattened counts (not a flattened tree's) and the SAH
    cost per depth."""
    scene = instanced_scene((24, 18))
    scene.bvhlab.compare_frames = 1
    scene.bvhlab.compare_filepath = str(tmp_path / "compare.csv")
    scene.bvhlab.backend = "cpu"
    assert bpy.ops.bvhlab.compare() == {"FINISHED"}
    rows = harness.addon().state.comparisons[scene.session_uid]
    flat = 12 + 4 * 968
    assert all(r["instances"] == 5 and r["primitives"] == 980 and r["primitives_flattened"] == flat for r in rows)
    for r in rows:  # per depth of the tree TLAS and BLASes make together: adds up to the two-level cost
        assert len(r["sah_cost_per_depth"]) > 1 and np.isclose(sum(r["sah_cost_per_depth"]), r["sah_cost"], rtol=1e-5)
    header = next(csv.reader((tmp_path / "compare.csv").open()))
    assert {"instances", "tlas_sah_cost", "primitives_flattened"} <= set(header)


def _instance_boxes_now():
    """The instances' world boxes of a fresh export and build of the scene as it is now."""
    lo, hi = bvhlab.build(bvhlab.blender.export_scene(bpy.context, require_camera=False)).world_boxes()
    return _sorted_rows(lo, hi, np.zeros(len(lo)))


def test_the_sidebars_boxes_follow_a_moved_instance_and_the_animation():
    """With the boxes shown, moving an instancer in the viewport (a depsgraph update) and scrubbing
    an animation (frame_set) update the tree Build made: a new TLAS only (no mesh tree built or
    updated), whose leaves are the instances' boxes of a fresh export and build at that moment."""
    scene = instanced_scene()
    counts = _addon("trees").counts
    assert bpy.ops.bvhlab.build() == {"FINISHED"} and scene.bvhlab.overlay_show
    built = harness.addon().state.tree_for(scene)
    levels = _addon("overlay.levels")

    def leaves():
        boxes = levels.two_level_boxes(built.bvh, "tlas", 0, 63, leaves_only=True)
        return _sorted_rows(boxes.lo, boxes.hi, np.zeros(len(boxes.lo)))

    before = counts.snapshot()
    shown = leaves()
    bpy.data.objects["Instance 2"].location.z += 2.0
    bpy.context.view_layer.update()
    assert _addon("follow").wait()  # the first sync after Build reads everything: on the worker
    assert built.tree.last.action == "placed", built.tree.last
    after = counts.snapshot()
    assert after[:3] == before[:3] and after[3] == before[3] + 1, (before, after)
    assert not np.array_equal(leaves(), shown)
    np.testing.assert_allclose(leaves(), _instance_boxes_now(), atol=1e-5)

    empty = bpy.data.objects["Instance 3"]
    empty.keyframe_insert("location", frame=1)
    empty.location.x += 3.0
    empty.keyframe_insert("location", frame=10)
    scene.frame_set(1)
    assert _addon("follow").wait()
    at_start = leaves()
    scene.frame_set(5)
    assert _addon("follow").wait()
    assert not np.array_equal(leaves(), at_start), "scrubbing did not move the boxes"
    np.testing.assert_allclose(leaves(), _instance_boxes_now(), atol=1e-5)
    assert counts.snapshot()[:2] == before[:2], "scrubbing built a tree"
