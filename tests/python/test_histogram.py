"""The histogram of a traversal counter (issue 35) and the legends of the colourings: the counts
add up to the pixels and are numpy's over the same bins, a one-sphere scene puts its pixels in the
bins a slab test says, the strip's bars and every legend's pixels are the palette's colours where
they belong (the CLI's render, the heatmap mode's scale, snapshot pictures and sheets)."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

import bvhlab
from bvhlab import counters, histogram, legend, palette
from bvhlab.library import showcase

sys.path.insert(0, str(Path(__file__).parent))
from png_reader import read_png  # noqa: E402

W, H = 48, 32


def _planes(scene, samples_per_axis=1, width=W, height=H):
    job = bvhlab.Renderer("cpu").start(
        scene, bvhlab.build(scene), width, height, traversal_counters=True, samples_per_axis=samples_per_axis
    )
    job.run()
    return job.result(color=False, depth=False, cost=False, counters=True).counters


def _numpy_counts(values, h):
    """numpy's histogram over the same edges, the values outside them put in the end bins."""
    return np.histogram(np.clip(values, h.edges[0], h.edges[-1]), bins=h.edges)[0]


@pytest.mark.parametrize("samples_per_axis", [1, 2])
def test_counts_add_up_to_the_pixels_and_are_numpys(samples_per_axis):
    c = _planes(showcase.whitted(), samples_per_axis)
    for name in counters.COUNTERS:
        values = counters.counter_plane(c, name)
        for value_range in (None, (1.0, 5.0), (0.0, 200.0), (0.25, 2.75)):
            h = histogram.counter_histogram(values, name, value_range)
            assert h.pixels == W * H and h.counts.dtype == np.int64
            np.testing.assert_array_equal(h.counts, _numpy_counts(values, h))
            lo, hi = h.value_range
            assert h.below == int((values < lo).sum()) and h.above == int((values > hi).sum())
            assert h.edges[0] <= max(lo, values.min()) or h.below  # the range is covered
            assert len(h.counts) <= histogram.DEFAULT_BINS
    box = counters.counter_plane(c, "box_tests")
    h = histogram.counter_histogram(box, "box_tests")
    assert h.value_range == counters.auto_range(box) and h.auto  # the image's colour range
    p = h.percentiles
    assert (p["p50"], p["p90"], p["p99"], p["max"]) == tuple(np.percentile(box, [50, 90, 99, 100]))
    assert h.mean == pytest.approx(float(box.mean()))


def test_whole_counts_get_bins_of_whole_numbers_and_averages_bins_of_their_grid():
    values = np.array([0, 1, 1, 2, 3, 3, 3, 7, 40], np.float32)
    h = histogram.counter_histogram(values, "prim_tests", (0.0, 7.0))
    np.testing.assert_array_equal(h.edges, np.arange(9) - 0.5)  # one bin per whole number
    assert h.counts.tolist() == [1, 2, 1, 3, 0, 0, 0, 2] and h.above == 1  # 40: in the last bin
    wide = histogram.counter_histogram(np.arange(100, dtype=np.float32), "box_tests", (0.0, 99.0), bins=32)
    assert (np.diff(wide.edges) == 4).all() and len(wide.counts) == 25  # 4 whole numbers a bin
    assert (wide.counts == 4).all()
    assert h.bin_labels() == ["0", "1", "2", "3", "4", "5", "6", "7+"]
    assert wide.bin_labels()[:2] == ["0-3", "4-7"] and wide.bin_labels()[-1] == "96-99"
    above_two = histogram.counter_histogram(values, "prim_tests", (2.0, 7.0))
    assert above_two.below == 3 and above_two.bin_labels()[0] == "≤ 2" and above_two.counts[0] == 4
    quarters = np.arange(0, 10, 0.25, dtype=np.float32)  # averages over 2 × 2 samples
    q = histogram.counter_histogram(quarters, "box_tests", (0.0, 9.75), bins=40)
    assert (q.counts == 1).all() and histogram.value_grid(quarters) == 4
    assert q.bin_labels()[:3] == ["0", "0.25", "0.5"]
    uneven = np.float32([0.1234, 0.4567, 2.71])
    assert histogram.value_grid(uneven) is None
    assert np.allclose(histogram.counter_histogram(uneven, "box_tests", (0, 3), bins=3).edges, [0, 1, 2, 3])
    with pytest.raises(ValueError, match="counter"):
        histogram.counter_histogram(values, "boxes")
    with pytest.raises(ValueError, match="LO < HI"):
        histogram.counter_histogram(values, "box_tests", (3.0, 3.0))
    with pytest.raises(ValueError, match="finite"):
        histogram.counter_histogram(np.float32([1, np.nan]), "box_tests")


@pytest.mark.parametrize("q", [9, 25, 36, 49, 81])
def test_averages_of_q_samples_at_the_range_top_lie_in_a_bin(q):
    """Averages over 3×3 (5×5, ...) samples are float32 k/q: the range's top, say float32(34/9),
    times 9 is 33.9999990, so the grid's bins ended at 33/9 and the top value's pixels were in no
    bin of their own (probe: 10 pixels at 3.78 past the last edge, 3.72). Every value of the range
    now lies within the edges, in the bin of its own grid point."""
    k = np.arange(0, 4 * q + 1)
    values = (k / q).astype(np.float32)
    for top in values[q:]:
        h = histogram.counter_histogram(values, "prim_tests", (0.0, float(top)))
        inside = values[values <= top]
        assert h.edges[0] <= inside.min() and inside.max() <= h.edges[-1], (q, top, h.edges[-2:])
        assert h.counts.sum() == len(values) and h.above == len(values) - len(inside)
        # each value in the bin whose edges hold it (the top's pixels in the last bin by value)
        bins = np.searchsorted(h.edges, inside.astype(np.float64), side="right") - 1
        assert (bins < len(h.counts)).all()


def test_percentiles_from_distinct_values_are_numpys():
    rng = np.random.default_rng(3)
    for trial in range(300):
        n = int(rng.integers(1, 400))
        grid = (1, 4, 9)[trial % 3]
        values = (rng.integers(0, 60, n) / grid).astype(np.float32)
        if trial % 5 == 0:
            values = (rng.random(n) * 30).astype(np.float32)  # on no grid
        distinct, counts = np.unique(values, return_counts=True)
        for q in (0, 37.5, 50, 90, 99, 100):
            assert histogram.percentile(distinct, counts, q) == float(np.percentile(values, q)), (trial, q)
    big = np.repeat(np.float32([1, 2, 5]), [10**6, 3, 10**4])
    assert histogram.counter_histogram(big, "box_tests").value_range == counters.auto_range(big)


def _entered(scene, lo, hi, width, height):
    """Which pixels' primary rays enter the box lo..hi (a slab test on the tracer's own rays)."""
    from bvhlab import _core
    from bvhlab._render_scene import SceneCache
    from bvhlab._render_settings import render_settings

    tree = bvhlab.build(scene)
    settings = render_settings(scene, tree, width, height, bvhlab.RenderOptions(samples_per_axis=1), None)
    rs = SceneCache().get(scene, tree)
    out = np.zeros((height, width), bool)
    for y in range(height):
        for x in range(width):
            o, d, tmin, tmax = (np.float64(v) for v in _core.pixel_ray(rs, settings, x, y, 0))
            with np.errstate(divide="ignore"):
                t0, t1 = (lo - o) / d, (hi - o) / d
            out[y, x] = max(np.minimum(t0, t1).max(), tmin) <= min(np.maximum(t0, t1).min(), tmax)
    return out


def test_a_one_sphere_scene_puts_each_pixel_in_the_bin_of_its_known_count():
    """One sphere: the tree is one leaf, so a ray that enters its box tests one primitive, and one
    that misses tests none. The pixel at the centre (on the sphere) is in bin 1; bin 1 holds as
    many pixels as a slab test finds entering the box."""
    camera = bvhlab.Camera(position=(0, -5, 0), look_at=(0, 0, 0), up=(0, 0, 1), fov_y=40)
    scene = bvhlab.Scene(spheres=np.float32([[0, 0, 0, 1]]), camera=camera)
    w, h = 32, 24
    prim_tests = counters.counter_plane(_planes(scene, 1, w, h), "prim_tests")
    hist = histogram.counter_histogram(prim_tests, "prim_tests", (0.0, 4.0))
    assert hist.edges[1] <= prim_tests[h // 2, w // 2] == 1 < hist.edges[2]
    entered = _entered(scene, np.float64([-1, -1, -1]), np.float64([1, 1, 1]), w, h)
    assert 0 < entered.sum() < w * h
    assert hist.counts.tolist() == [w * h - entered.sum(), entered.sum(), 0, 0, 0]


def test_strip_bars_are_the_bins_heat_colours():
    values = np.repeat(np.arange(10, dtype=np.float32), np.arange(1, 11)).reshape(1, -1)  # k appears k + 1 times
    h = histogram.counter_histogram(values, "box_tests", (0.0, 9.0))
    strip = histogram.histogram_strip(h, 40)  # widened: 10 bars of at least MIN_BAR_WIDTH
    width = histogram.strip_width(h, 40)
    assert strip.shape[1] == width >= 2 * legend.MARGIN + 10 * histogram.MIN_BAR_WIDTH
    columns, heights = histogram.bar_columns(h, width), histogram.bar_heights(h)
    assert heights[-1] == histogram.PLOT_HEIGHT and heights[0] == round(histogram.PLOT_HEIGHT / 10)
    bottom = histogram.PLOT_TOP + histogram.PLOT_HEIGHT
    for k in range(10):
        column = strip[histogram.PLOT_TOP : bottom, (columns[k] + columns[k + 1]) // 2, :3]
        lit = (column == palette.heat(palette.scaled(np.float32([k]), 0.0, 9.0))[0]).all(-1)
        assert lit.sum() == heights[k] and lit[-heights[k] :].all()  # bottom-aligned, its colour
        assert (column[~lit] == np.float32(legend.BACKGROUND)).all()


def test_heatmap_legend_is_the_scale_the_image_uses():
    scene = showcase.whitted()
    tree = bvhlab.build(scene)
    options = bvhlab.RenderOptions(mode="heatmap", samples_per_axis=1, overlay_depth=(1, 3))
    job = bvhlab.Renderer("cpu").start(scene, tree, W, H, options=options)
    job.run()
    r = job.result(depth=False, heat=True)
    scale = r.timings["heatmap_scale"]
    assert scale == 8 * tree.stats["height"]  # the core's default
    assert bvhlab.Renderer("cpu").start(scene, tree, 8, 8, heatmap_scale=5.0).timings["heatmap_scale"] == 5.0
    heat = palette.heat(palette.scaled(r.cost, 0.0, scale)).reshape(H, W, 3)
    np.testing.assert_allclose(r.heat[..., :3], heat, atol=1e-6)  # the legend's 0..scale is the image's
    image = legend.render_legends(r.color, options, scale, tree_height=tree.stats["height"])
    bar = image[H + legend.MARGIN : H + legend.MARGIN + legend.BAR_HEIGHT, legend.MARGIN : W - legend.MARGIN, :3]
    np.testing.assert_allclose(bar[0], palette.heat(np.linspace(0, 1, W - 2 * legend.MARGIN)), atol=1e-6)
    below_bar = image[H + legend.heat_bar(W, 0, scale).shape[0] :]
    np.testing.assert_array_equal(below_bar, legend.depth_legend(W, range(1, 4)))  # then the depths' swatches
    deep = legend.render_legends(r.color, options.replace(mode="shade", overlay_depth=(2, 60)), tree_height=4)
    np.testing.assert_array_equal(deep[H:], legend.depth_legend(W, range(2, 4)))  # the depths the tree has
    plain = legend.render_legends(r.color, bvhlab.RenderOptions())
    assert plain is r.color  # shading without boxes: nothing to explain
    with pytest.raises(ValueError, match="scale"):
        legend.render_legends(r.color, options)


def test_cli_render_counter_writes_the_histogram_beside_the_image(tmp_path, capsys):
    from bvhlab.cli import main
    from bvhlab.cli.render_cmd import histogram_paths
    from bvhlab.png import linear_to_srgb

    out = tmp_path / "box.png"
    argv = ["render", "gen:whitted", "--width", str(W), "--height", str(H), "--backend", "cpu", "--out", str(out)]
    assert main([*argv, "--counter", "box_tests", "--samples-per-axis", "1"]) == 0
    strip_png, numbers = histogram_paths(out)
    values = np.load(out.with_suffix(".npy"))
    saved = json.loads(numbers.read_text())
    h = histogram.counter_histogram(values, "box_tests")
    assert saved["counts"] == h.counts.tolist() and sum(saved["counts"]) == W * H
    assert saved["bins"] == [[a, b] for a, b in zip(h.edges[:-1], h.edges[1:])]
    assert saved["percentiles"]["p99"] == float(np.percentile(values, 99)) and saved["auto_range"]
    png = read_png(strip_png)[..., :3].astype(int)
    want = (linear_to_srgb(histogram.histogram_strip(h, W)[..., :3]) * 255 + 0.5).astype(int)
    assert png.shape == want.shape and np.abs(png - want).max() <= 1
    assert f"p99 {saved['percentiles']['p99']:g}" in capsys.readouterr().out


def _snapshot_rgb(path):
    import matplotlib.pyplot as plt

    return np.round(plt.imread(path)[..., :3] * 255).astype(int)


def test_snapshot_picture_and_sheet_carry_their_depth_legend(tmp_path):
    from bvhlab.snapshot import run_sheet, run_snapshot

    try:
        picture = run_snapshot("gen:five_spheres", {}, tmp_path / "s.png", (0, 2), 160, 120)
    except RuntimeError as e:
        pytest.skip(str(e))
    rgb = _snapshot_rgb(picture)
    strip = legend.depth_legend(160, range(3))
    assert rgb.shape[:2] == (120 + strip.shape[0], 160)
    expected = np.round(np.clip(strip[..., :3], 0, 1) * 255).astype(int)  # the raster's bytes
    np.testing.assert_array_equal(rgb[120:], expected)
    for d, colour in enumerate(np.round(palette.depth(range(3)) * 255).astype(int)):
        assert (rgb[:120] == colour).all(-1).sum() > 20, f"depth {d}'s lines are the swatch's colour"
    sheet = _snapshot_rgb(run_sheet("gen:five_spheres", {}, tmp_path / "sheet.png", 160, 120))
    for colour in np.round(palette.depth(range(3)) * 255).astype(int):
        assert (sheet == colour).all(-1).sum() >= 100, "each panel's swatch in its depth's colour"
