"""The sidebar's Traversal Counters (issue 35) under bpy 4.2, the add-on enabled in place: Render
Counter's image is the CPU reference's counter on the heat ramp with its scale bar and its
histogram is bvhlab.histogram's of the same counts; Compare Two Trees' image equals the one
`bvhlab compare --counter-diff` writes for the same scene (exported to a file) and settings; the
sidebar's Render image carries the legends of its colourings."""

import json
import sys
from pathlib import Path

import blender_checks  # noqa: F401
import harness
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from png_reader import read_png  # noqa: E402

#: The panel's build settings that make Compare Two Trees' trees the CLI's (the report's settings).
REPORT_PANEL = {"axis": "largest", "max_leaf_size": 1, "bin_bounds": "centroids", "sah_block": "1"}


@pytest.fixture(scope="module")
def scene():
    import bpy

    harness.enable_addon_from_source()
    scene = harness.boxes_scene()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=1.0, location=(0.0, 0.5, 0.8))
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 64, 48, 100
    settings = scene.bvhlab
    settings.backend, settings.render_supersampling = "cpu", 1
    return scene


def _image(name):
    import bpy

    image = bpy.data.images[name]
    w, h = image.size
    pixels = np.empty(w * h * 4, np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(h, w, 4)[::-1]  # row 0 at the top


def _state():
    return __import__(harness.addon().__name__ + ".state", fromlist=["counter_results"])


def _exported(bpy):
    from bvhlab.blender import export_scene

    return export_scene(bpy.context, scope=bpy.context.scene.bvhlab.scope)


@pytest.mark.parametrize("counter, manual", [("prim_tests", None), ("box_hits", (1.0, 6.0))])
def test_render_counter_image_and_histogram_are_the_cpu_references(scene, counter, manual):
    import bpy

    import bvhlab
    from bvhlab import counters, histogram

    settings = scene.bvhlab
    settings.viewport_counter = counter
    settings.counter_range_auto = manual is None
    if manual is not None:
        settings.counter_range_min, settings.counter_range_max = manual
    assert bpy.ops.bvhlab.render_counter() == {"FINISHED"}
    state = _state()
    tree = state.tree_for(scene).bvh
    job = bvhlab.Renderer("cpu").start(
        _exported(bpy), tree, 64, 48, options=settings.render_options().replace(traversal_counters=True)
    )
    job.run()
    values = counters.counter_plane(job.result(counters=True).counters, counter)
    assert len(np.unique(values)) > 2, "a counter that varies"
    expected, _ = counters.counter_image(values, manual)
    np.testing.assert_array_equal(_image("BVH Render"), expected)  # with its scale bar
    hist = state.counter_results[state.key(scene)]["histogram"]
    assert hist.pixels == 64 * 48 and hist.counter == counter and hist.auto == (manual is None)
    bins = harness.addon().engine.counter_view.SIDEBAR_BINS
    np.testing.assert_array_equal(hist.counts, histogram.counter_histogram(values, counter, manual, bins).counts)
    assert len(hist.bin_labels()) == len(hist.counts) <= bins


def test_two_trees_difference_is_the_clis(scene, tmp_path, capsys):
    import bpy

    from bvhlab import counters
    from bvhlab.cli import main
    from bvhlab.compare import counter_diff
    from bvhlab.png import linear_to_srgb

    settings = scene.bvhlab
    settings.counter_range_auto = True
    for name, value in REPORT_PANEL.items():
        setattr(settings, name, value)
    settings.viewport_counter = "box_tests"
    settings.counter_diff_first, settings.counter_diff_second = "median", "sah12"
    assert bpy.ops.bvhlab.counter_diff() == {"FINISHED"}
    ours = _image("BVH Counter Difference")
    summary = _state().counter_results[_state().key(scene)]["difference"]

    scene_file = _exported(bpy).save(tmp_path / "boxes.npz")  # the same scene for the CLI
    argv = ["compare", str(scene_file), "--counter-diff", "median,sah12", "--counter", "box_tests"]
    out = tmp_path / "diff"
    assert main([*argv, "--width", "64", "--height", "48", "--backend", "cpu", "--out", str(out)]) == 0
    stem = out / "counter_diff_box_tests_median_sah12"
    a, b, difference = np.load(stem.with_suffix(".npy"))
    assert (difference != 0).any(), "two trees that differ somewhere"
    cli = json.loads(stem.with_suffix(".json").read_text())
    assert summary == cli
    image, span = counters.difference_image(difference, cli["span"])
    np.testing.assert_array_equal(ours, image)  # the CLI's image, legend included
    side = _image("BVH Two Trees")
    np.testing.assert_array_equal(side, counter_diff.side_by_side(a, b)[0])  # the auto range of both
    for path, pixels in ((stem.with_suffix(".png"), ours), (out / f"{stem.name}_side_by_side.png", side)):
        png = read_png(path)[..., :3].astype(int)
        assert np.abs(png - (linear_to_srgb(pixels[..., :3]) * 255 + 0.5).astype(int)).max() <= 1
    settings.counter_diff_second = "median"
    with pytest.raises(RuntimeError, match="two different methods"):  # one tree against itself: said
        bpy.ops.bvhlab.counter_diff()


def test_render_image_carries_the_legends_of_its_colourings(scene):
    import bpy

    from bvhlab import legend, palette

    settings = scene.bvhlab
    settings.render_mode, settings.render_overlay, settings.overlay_color_by_depth = "heatmap", True, True
    settings.overlay_depth_min, settings.overlay_depth_max = 1, 2
    try:
        assert bpy.ops.bvhlab.render() == {"FINISHED"}
    finally:
        settings.render_mode, settings.render_overlay = "shade", False
    image = _image("BVH Render")
    tree = _state().tree_for(scene).bvh
    scale = 8 * tree.stats["height"]  # the core's default heatmap scale
    bar, swatches = legend.heat_bar(64, 0, scale), legend.depth_legend(64, [1, 2])
    assert image.shape == (48 + bar.shape[0] + swatches.shape[0], 64, 4)
    np.testing.assert_array_equal(image[48 : 48 + bar.shape[0]], bar)
    row = image[48 + legend.MARGIN, legend.MARGIN : 64 - legend.MARGIN, :3]
    np.testing.assert_allclose(row, palette.heat(np.linspace(0, 1, 64 - 2 * legend.MARGIN)), atol=1e-6)
    np.testing.assert_array_equal(image[48 + bar.shape[0] :], swatches)
    for colour in palette.depth([1, 2]):
        assert (image[48 + bar.shape[0] + legend.MARGIN, :, :3] == colour).all(-1).sum() >= 2 * legend.TEXT_HEIGHT
