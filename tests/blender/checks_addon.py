"""Operator checks (the add-on must be enabled: harness.enable_addon_from_source or an installed
zip): Build against bvhlab.build on the same export, overlay box counts, exported stats files,
Render against Blender's own ray casts, Compare, and bad input reported without a crash."""

from __future__ import annotations

import csv
import json
import math

import bpy
import harness
import numpy as np

import bvhlab
from bvhlab.blender import export_scene
from bvhlab.bvh import method_from_label as method_kwargs

BUILD_VARIANTS = (
    {"method": "sah", "bins": 12},
    {"method": "sah", "bins": 32, "bin_bounds": "centroids"},
    {"method": "median"},
    {"method": "mean", "max_leaf_size": 4},
    {"method": "sweep_sah", "axis": "best"},
    {"method": "sah", "bins": 8, "max_leaf_size": 8, "sah_block": 1},
    {"method": "sah", "bins": 8, "max_leaf_size": 8, "sah_block": 16},
)
#: Scenes the Build operator is checked on, with the variants (the large one gets the quick two).
BUILD_SCENES = {"five_spheres": BUILD_VARIANTS, "whitted": BUILD_VARIANTS, "suzanne_250k": BUILD_VARIANTS[:2]}


def _configure(**settings):
    for name, value in settings.items():
        # the SAH block is an enum of powers of two (its identifiers are strings)
        setattr(bpy.context.scene.bvhlab, name, str(value) if name == "sah_block" else value)


def _built():
    return harness.addon().state.tree_for(bpy.context.scene)


def check_build_matches_direct(name: str, variants=BUILD_VARIANTS) -> None:
    """For each variant: the operator's tree has the stats and the nodes of bvhlab.build on the
    scene exported directly (only the build time may differ)."""
    harness.open_scene(name)
    for variant in variants:
        _configure(
            scope="visible", method="sah", bins=12, bin_bounds="box", axis="largest", max_leaf_size=1, sah_block=4
        )
        _configure(**variant)
        assert bpy.ops.bvhlab.build() == {"FINISHED"}
        built = _built()
        direct = bvhlab.build(
            export_scene(bpy.context, require_camera=False),
            **{"method": "sah", "bins": 12, "bin_bounds": "box", "axis": "largest", "max_leaf_size": 1, "sah_block": 4}
            | variant,
        )
        ours, theirs = built.bvh.stats, direct.stats
        for key in theirs:
            if key != "build_ms":
                assert ours[key] == theirs[key], (name, variant, key, ours[key], theirs[key])
        assert built.bvh.nodes.tobytes() == direct.nodes.tobytes(), (name, variant)


def check_overlay_ranges() -> None:
    """The overlay's table holds, for every depth range, exactly the nodes (or leaves) at those
    depths, with the boxes bvh.boxes gives; the depth settings stay within the tree's height."""
    from importlib import import_module

    batch = import_module(harness.addon().__name__ + ".overlay.batch")
    harness.open_scene("whitted")
    _configure(method="sah", max_leaf_size=1, overlay_depth_min=0, overlay_depth_max=3)
    bpy.ops.bvhlab.build()
    bvh = _built().bvh
    stats = bvh.stats
    height = stats["height"]
    table, leaves = batch.BoxTable(bvh), batch.BoxTable(bvh, leaves_only=True)
    leaf_set = {(tuple(node["lo"]), tuple(node["hi"])) for node in bvh.nodes[bvh.is_leaf]}
    for depth_min, depth_max in ((0, 0), (1, 2), (3, height - 1), (0, height - 1), (height - 1, height - 1)):
        first, count = table.depth_slice(depth_min, depth_max)
        assert count == sum(stats["nodes_per_depth"][depth_min : depth_max + 1])
        lo, hi, depth = bvh.boxes(depth_min, depth_max)
        rows = table.rows[first : first + count]
        assert np.array_equal(rows[:, 0:3], lo) and np.array_equal(rows[:, 4:7], hi)
        assert np.array_equal(rows[:, 3], depth)
        first, leaf_count = leaves.depth_slice(depth_min, depth_max)
        assert leaf_count == sum(stats["leaves_per_depth"][depth_min : depth_max + 1])
        leaf_rows = leaves.rows[first : first + leaf_count]
        assert np.all((leaf_rows[:, 3] >= depth_min) & (leaf_rows[:, 3] <= depth_max))
        assert all((tuple(r[0:3]), tuple(r[4:7])) in leaf_set for r in leaf_rows), "a non-leaf in the leaves"
    assert table.depth_slice(height, height + 3)[1] == 0
    settings = bpy.context.scene.bvhlab
    settings.overlay_depth_max = 60
    assert settings.overlay_depth_max == height - 1
    settings.overlay_depth_min = height + 5
    assert settings.overlay_depth_min == height - 1 and settings.overlay_depth_max == height - 1
    settings.overlay_depth_max = 1
    assert settings.overlay_depth_min == 1


def check_build_shows_overlay() -> None:
    """Pressing Build is asking to see the boxes: the overlay is on afterwards, even when the user
    had never ticked "Viewport Boxes"."""
    harness.boxes_scene()
    settings = bpy.context.scene.bvhlab
    assert not settings.overlay_show, "the overlay must start off (nothing to show before a build)"
    assert bpy.ops.bvhlab.build() == {"FINISHED"}
    assert settings.overlay_show, "Build left the overlay off"


def check_export_stats(tmp_dir) -> None:
    """JSON holds bvh.stats unchanged; the CSV's rows give back every value and list."""
    harness.open_scene("five_spheres")
    _configure(method="mean")
    bpy.ops.bvhlab.build()
    path = tmp_dir / "five_spheres_stats.json"
    assert bpy.ops.bvhlab.export_stats(filepath=str(path)) == {"FINISHED"}
    stats = _built().bvh.stats
    written = json.loads(path.read_text())
    assert written["stats"] == stats and written["about"]["settings"]["method"] == "mean"
    from_csv: dict = {}
    with path.with_suffix(".csv").open() as f:
        for row in csv.DictReader(f):
            if row["index"]:
                from_csv.setdefault(row["metric"], []).append(int(row["value"]))
            else:
                from_csv[row["metric"]] = row["value"]
    for key, value in stats.items():
        if isinstance(value, list):
            assert from_csv[key] == value, key
        elif isinstance(value, (int, float)):
            assert math.isclose(float(from_csv[key]), value), key
        else:
            assert from_csv[key] == str(value), key


def blender_hit_mask(scene, camera, width: int, height: int) -> np.ndarray:
    """(height, width) bool, row 0 at the top: does a pinhole ray through each pixel centre hit
    anything, by Blender's own scene.ray_cast (independent of bvhlab's trees and tracer)."""
    position, look_at, up = (np.array(v, np.float64) for v in (camera.position, camera.look_at, camera.up))
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    tan = math.tan(math.radians(camera.fov_y) / 2)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    mask = np.zeros((height, width), bool)
    for y in range(height):
        for x in range(width):
            px = ((x + 0.5) / width * 2 - 1) * tan * width / height
            py = (1 - (y + 0.5) / height * 2) * tan
            direction = forward + px * right + py * true_up
            mask[y, x] = scene.ray_cast(depsgraph, position.tolist(), direction.tolist())[0]
    return mask


def check_render() -> None:
    """Render on the CPU backend: the Image "BVH Render" has the scene's resolution, and its
    non-sky pixels are where Blender's ray casts hit (boundary pixels aside)."""
    scene = harness.boxes_scene()
    _configure(backend="cpu", render_bounces=2, render_samples=1, render_overlay=False, render_mode="shade")
    assert bpy.ops.bvhlab.render() == {"FINISHED"}
    image = bpy.data.images["BVH Render"]
    width, height = scene.render.resolution_x, scene.render.resolution_y
    assert tuple(image.size) == (width, height)
    pixels = np.empty(width * height * 4, np.float32)
    image.pixels.foreach_get(pixels)
    top_first = pixels.reshape(height, width, 4)[::-1]
    exported = export_scene(bpy.context)
    drawn = np.abs(top_first[..., :3] - np.array(exported.sky)).max(-1) > 0.02
    hits = blender_hit_mask(scene, exported.camera, width, height)
    padded = np.pad(hits, 1, mode="edge")
    neighbours = [padded[1 + dy : 1 + dy + height, 1 + dx : 1 + dx + width] for dy in (-1, 0, 1) for dx in (-1, 0, 1)]
    interior = np.all(neighbours == hits, axis=0)  # pixels away from a silhouette
    assert hits.any() and (~hits).any()
    agreement = (drawn == hits)[interior].mean()
    assert agreement > 0.99, f"only {agreement:.3f} of the interior pixels agree with Blender's ray casts"
    assert harness.addon().state.last_render[harness.addon().state.key(scene)]["backend"] == "cpu"


def check_compare(tmp_dir) -> None:
    """Every split method gets a row with the height of a direct build, written as CSV."""
    harness.boxes_scene()
    path = tmp_dir / "compare.csv"
    _configure(backend="cpu", compare_frames=1, compare_filepath=str(path), axis="largest", max_leaf_size=1)
    assert bpy.ops.bvhlab.compare() == {"FINISHED"}
    with path.open() as f:
        rows = list(csv.DictReader(f))
    methods = {row["method"] for row in rows}
    assert methods == {"median", "mean", "midpoint", "sah12", "sah32", "sweep_sah", "lbvh"}, methods
    exported = export_scene(bpy.context)
    for row in rows:
        direct = bvhlab.build(
            exported, axis="largest", max_leaf_size=1, **method_kwargs(row["method"])
        )  # as configured
        assert int(row["height"]) == direct.stats["height"] and float(row["frame_ms"]) > 0
    assert len(harness.addon().state.comparisons[harness.addon().state.key(bpy.context.scene)]) == len(rows)


def _expect_report(operator, fragment: str) -> None:
    """An ERROR report reaches a script as RuntimeError; the message must say what is wrong."""
    try:
        operator()
    except RuntimeError as error:
        assert fragment in str(error), f"'{fragment}' not in '{error}'"
        return
    raise AssertionError(f"no error report containing '{fragment}'")


def _still_alive() -> None:
    harness.boxes_scene()
    _configure(scope="visible")
    assert bpy.ops.bvhlab.build() == {"FINISHED"}


def check_bad_input_reports() -> None:
    """Empty selection, a NaN vertex, no camera: an ERROR report naming the problem, then Blender
    still runs operators."""
    harness.boxes_scene()
    _configure(scope="selected")
    for obj in bpy.context.scene.objects:
        obj.select_set(False)
    _expect_report(bpy.ops.bvhlab.build, "no mesh in scope")
    _still_alive()
    bpy.data.objects["Box C"].data.vertices[0].co.z = float("nan")
    _expect_report(bpy.ops.bvhlab.build, "Box C")
    _still_alive()
    bpy.context.scene.camera = None
    assert bpy.ops.bvhlab.build() == {"FINISHED"}, "a tree needs no camera"
    _expect_report(bpy.ops.bvhlab.render, "no camera")
    _still_alive()


def check_render_without_light() -> None:
    """No light: the render goes on with bvhlab's default light and says so in a WARNING."""
    harness.boxes_scene()
    bpy.data.objects.remove(bpy.data.objects["Light"])
    _configure(backend="cpu", render_bounces=1)
    assert bpy.ops.bvhlab.render() == {"FINISHED"}
    state = harness.addon().state
    level, text = state.messages[state.key(bpy.context.scene)]
    assert level == "WARNING" and "no visible light" in text, (level, text)
    _still_alive()


def check_no_vulkan_reported() -> None:
    """backend="vulkan" where no Vulkan driver loads (run with VK_DRIVER_FILES pointing nowhere)."""
    harness.boxes_scene()
    _configure(backend="vulkan")
    _expect_report(bpy.ops.bvhlab.render, "No Vulkan")
    _still_alive()
