"""Traversal counters per pixel (issue 35): each pixel's counters against the traversal record of
its primary ray (Bvh.trace_pixel: box tests = nodes visited, box hits, primitive tests, primitive
hits), instance hits against the instances' world boxes, the Vulkan tracer against the CPU
reference exactly, and the images: auto range, scale bar and difference of two trees."""

import dataclasses

import numpy as np
import pytest

import bvhlab
from bvhlab import counters, legend, palette
from bvhlab.compare import counter_diff
from bvhlab.compare.counter_diff import counter_difference, counter_planes
from bvhlab.inspect.ray_record import trace_pixel
from bvhlab.library import procedural, showcase

W, H = 48, 32


def _counters(scene, bvh, renderer="cpu", width=W, height=H, **options):
    r = renderer if isinstance(renderer, bvhlab.Renderer) else bvhlab.Renderer(renderer)
    job = r.start(scene, bvh, width, height, traversal_counters=True, **options)
    job.run()
    return job.result(depth=False, counters=True)


def _recorded(rec) -> list:
    """The five counters of a traversal record (a flat tree: no instances)."""
    return [rec.box_tests, rec.box_hits, rec.prim_tests, int(rec.prim_closer.sum()), 0]


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_pixel_counters_are_the_recorded_traversal(traversal):
    scene = showcase.whitted()  # reflection and refraction: secondary rays are not counted
    bvh = bvhlab.build(scene, max_leaf_size=2)
    options = bvhlab.RenderOptions(traversal=traversal, samples_per_axis=1)
    result = _counters(scene, bvh, options=options)
    c = result.counters
    assert c.shape == (H, W, len(counters.COUNTERS)) and counters.COUNTERS[0] == "box_tests"
    np.testing.assert_array_equal(c[..., 0], result.cost)  # the heatmap's cost is the box_tests counter
    job = bvhlab.Renderer("cpu").start(scene, bvh, W, H, options=options)  # no counters kept: the same picture
    job.run()
    plain = job.result(depth=False)
    np.testing.assert_array_equal(plain.cost, result.cost)
    np.testing.assert_array_equal(plain.color, _counters(scene, bvh, options=options).color)
    assert len(np.unique(c[..., 3])) > 1 and (c[..., 2] > c[..., 3]).any(), "the counters must vary"
    for y in range(0, H, 3):
        for x in range(0, W, 4):
            rec = trace_pixel(scene, bvh, x, y, width=W, height=H, options=options)
            assert c[y, x].tolist() == _recorded(rec), (x, y)


def _renderer(backend: str) -> bvhlab.Renderer:
    """The CPU reference, or Vulkan under the validation layer (the test skipped without Vulkan)."""
    if backend == "cpu":
        return bvhlab.Renderer("cpu")
    try:
        return bvhlab.Renderer("vulkan", validation=True)
    except bvhlab.VulkanUnavailable as e:
        pytest.skip(str(e))


@pytest.mark.parametrize("backend", ["cpu", pytest.param("vulkan", marks=pytest.mark.vulkan)])
def test_overlay_lines_change_neither_the_counters_nor_the_picture_beneath(backend):
    """The probe's case: `render --counter box_tests --bvh-depth 3:4` changed 1,908 of 76,800
    pixels' counters (the primary walk stopped at the overlay's line: a pixel 13 box tests with the
    boxes drawn, 21 without, 21 recorded by trace_pixel). A render that measures the walks (the
    counters, the heatmap mode) walks on to the surface and the line wins after: every counter and
    the heatmap's cost equal a render without boxes. A shaded render that keeps no counters still
    stops at the line (report §3.3: the frame's own work, lower where lines are), and its picture
    is the measured render's, bit for bit."""
    renderer = _renderer(backend)
    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    w, h = 96, 72

    def render(options):
        job = renderer.start(scene, bvh, w, h, options=options)
        job.run()
        return job.result(counters=options.traversal_counters)

    for traversal in ("stack", "stackless"):
        plain = bvhlab.RenderOptions(traversal=traversal, samples_per_axis=2)
        boxes = plain.replace(overlay_depth=(2, 5))
        counted = [render(o.replace(traversal_counters=True)) for o in (plain, boxes)]
        lines = (counted[1].color != counted[0].color).any(-1)
        assert lines.mean() > 0.05, "the boxes' lines cover many pixels"
        np.testing.assert_array_equal(counted[1].counters, counted[0].counters)
        np.testing.assert_array_equal(counted[1].cost, counted[0].cost)
        heat = [render(o.replace(mode="heatmap")) for o in (plain, boxes)]
        np.testing.assert_array_equal(heat[1].cost, heat[0].cost)
        shaded = render(boxes)  # no counters: cut at the lines
        np.testing.assert_array_equal(shaded.color, counted[1].color)
        assert (shaded.cost[lines] < counted[1].cost[lines]).mean() > 0.5, "the cut walk does less"


def _camera_on_box_planes():
    """Scenes whose camera lies on planes of the tree's boxes, with a mirror and a glass sphere in
    view: the bundled whitted.blend (camera at x = 0, where the floor's boxes end) and the generated
    whitted scene with its camera moved onto the floor's cell boundary x = 0. Primary rays start on
    a box's far plane and leave it; the tracer's box test took that plane as no bound (as for a ray
    parallel to it) and entered boxes the ray misses: 168 of 432 pixels of the blend's 24×18 render
    counted more than trace_pixel records (a floor pixel: 31 box tests against 19)."""
    blend, _ = bvhlab.library.load_scene("whitted")
    gen = showcase.whitted()
    camera = dataclasses.replace(gen.camera, position=(0.0, -9.0, 3.6))
    gen = bvhlab.Scene(
        triangles=gen.triangles,
        spheres=gen.spheres,
        materials=gen.materials,
        tri_material=gen.tri_material,
        sphere_material=gen.sphere_material,
        camera=camera,
        light=gen.light,
        sky=gen.sky,
    )
    return {"whitted.blend": blend, "gen:whitted, camera at x = 0": gen}


@pytest.mark.parametrize("backend", ["cpu", pytest.param("vulkan", marks=pytest.mark.vulkan)])
def test_every_pixel_of_a_camera_on_box_planes_is_its_recorded_traversal(backend):
    renderer = _renderer(backend)
    w, h = 24, 18
    differing = {}
    for name, scene in _camera_on_box_planes().items():
        materials = scene.materials
        shown = {int(m) for m in np.asarray(scene.sphere_material)}
        assert any(materials[m].transparent > 0 for m in shown) and any(materials[m].reflective > 0 for m in shown)
        bvh = bvhlab.build(scene)
        for traversal in ("stack", "stackless"):
            options = bvhlab.RenderOptions(traversal=traversal)
            c = _counters(scene, bvh, renderer, width=w, height=h, options=options).counters
            assert (c[..., 3] > 0).mean() > 0.5, "mostly surfaces in view"
            recorded = np.array(
                [
                    [_recorded(trace_pixel(scene, bvh, x, y, width=w, height=h, options=options)) for x in range(w)]
                    for y in range(h)
                ]
            )
            differing[f"{name}, {traversal}"] = int((c != recorded).any(-1).sum())
    assert differing == dict.fromkeys(differing, 0), f"pixels of {w * h} that differ: {differing}"
    if backend == "vulkan":
        assert renderer.validation_errors == 0, renderer.validation_messages()


def test_counters_average_the_samples():
    scene = showcase.five_spheres()
    bvh = bvhlab.build(scene)
    options = bvhlab.RenderOptions(samples_per_axis=2)
    c = _counters(scene, bvh, width=24, height=16, options=options).counters
    for x, y in ((12, 8), (3, 2), (20, 12)):
        recs = [trace_pixel(scene, bvh, x, y, width=24, height=16, options=options, sample=s) for s in range(4)]
        np.testing.assert_allclose(c[y, x], np.mean([_recorded(r) for r in recs], axis=0), rtol=1e-6)


def _moved(scene, move=(0.5, 0.25, 0.0)):
    """The flat scene as one instance of itself, moved (one identity instance renders flat)."""
    mesh_of, transforms = scene.instances()
    transforms = transforms.copy()
    transforms[0, :, 3] = move
    return bvhlab.Scene(
        triangles=scene.triangles,
        spheres=scene.spheres,
        instance_mesh=mesh_of,
        instance_transforms=transforms,
        camera=scene.camera,
    )


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_instance_hits_of_one_instance(traversal):
    flat = showcase.five_spheres()
    flat = bvhlab.Scene(triangles=flat.triangles, spheres=flat.spheres, camera=flat.camera)
    two = _moved(flat)
    tree = bvhlab.build(two)
    assert isinstance(tree, bvhlab.InstancedBvh) and tree.stats["tlas_nodes"] == 1
    a = _counters(flat, bvhlab.build(flat), traversal=traversal).counters
    b = _counters(two, tree, traversal=traversal).counters
    assert (a[..., 4] == 0).all()  # no instances in a flat scene
    entered = b[..., 4] == 1
    assert set(np.unique(b[..., 4])) == {0.0, 1.0}, "one instance: entered or not"
    assert (b[~entered][:, :4] == [1, 0, 0, 0]).all()  # the TLAS's one box, missed
    assert (b[entered][:, 0] >= 2).all() and (b[entered][:, 1] >= 1).all()  # then the mesh's tree
    assert (b[..., 3] <= b[..., 2]).all() and (b[..., 1] <= b[..., 0]).all()


def _slab_entry(lo, hi, o, d, tmin, tmax):
    """Entry distance of the ray into each box (inf where it misses within [tmin, tmax])."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t0, t1 = (lo - o) * inv, (hi - o) * inv
    near = np.nanmax(np.minimum(t0, t1), axis=1).clip(min=tmin)
    far = np.nanmin(np.maximum(t0, t1), axis=1).clip(max=tmax)
    return np.where(near <= far, near, np.inf)


def test_instance_hits_lie_between_the_boxes_the_ray_must_and_may_enter():
    from bvhlab import _core
    from bvhlab._render_scene import SceneCache
    from bvhlab._render_settings import render_settings
    from bvhlab.render_options import RenderOptions

    rng = np.random.default_rng(5)
    cells = [(x, y) for x in range(4) for y in range(3)]
    transforms = np.stack(
        [
            np.concatenate([np.eye(3) * rng.uniform(0.6, 1.0), [[2.2 * x], [2.2 * y], [rng.uniform(-1, 1)]]], 1)
            for x, y in cells
        ]
    ).astype(np.float32)
    mesh = showcase.five_spheres().triangles[:0]
    scene = bvhlab.Scene(
        triangles=mesh,
        meshes=[procedural.torus_knot(400)],
        instance_mesh=np.ones(len(cells), int),
        instance_transforms=transforms,
    )
    tree = bvhlab.build(scene)
    c = _counters(scene, tree).counters[..., 4]
    assert c.max() >= 2, "rays that enter several instances"
    lo, hi = tree.world_boxes()
    settings = render_settings(scene, tree, W, H, RenderOptions(), None)
    rs = SceneCache().get(scene, tree)
    for y in range(0, H, 2):
        for x in range(0, W, 3):
            o, d, tmin, tmax = _core.pixel_ray(rs, settings, x, y, 0)
            o, d = np.float64(o), np.float64(d)
            hit = tree.intersect(np.float32([o]), np.float32([d]), tmin=tmin, tmax=tmax)
            entry = _slab_entry(lo, hi, o, d, tmin, tmax)
            t = float(hit["t"][0])
            must = int((entry < t * (1 - 1e-3) - 1e-4).sum())  # in front of the hit: walked into
            may = int(np.isfinite(_slab_entry(lo - 1e-3, hi + 1e-3, o, d, tmin, tmax)).sum())
            assert must <= c[y, x] <= may, (x, y, must, c[y, x], may)


def test_counters_need_to_be_asked_for():
    scene = showcase.five_spheres()
    job = bvhlab.Renderer("cpu").start(scene, bvhlab.build(scene), 8, 8)
    job.run()
    with pytest.raises(ValueError, match="traversal counters"):
        job.result(counters=True)
    with pytest.raises(ValueError, match="counter"):
        counters.counter_index("boxes")


def test_vulkan_counters_equal_the_cpu_reference():
    try:
        vulkan = bvhlab.Renderer("vulkan", validation=True)
    except bvhlab.VulkanUnavailable as e:
        pytest.skip(str(e))
    flat = showcase.whitted()
    two = _moved(bvhlab.Scene(triangles=flat.triangles, spheres=flat.spheres, camera=flat.camera))
    for scene in (flat, two):
        tree = bvhlab.build(scene)
        for traversal in ("stack", "stackless"):
            # a small budget per dispatch: traces stop and resume mid-walk (the saved counters)
            for steps in (None, 40):
                options = bvhlab.RenderOptions(traversal=traversal, samples_per_axis=2, steps_per_dispatch=steps)
                vk = _counters(scene, tree, vulkan, options=options).counters
                cpu = _counters(scene, tree, options=options).counters
                np.testing.assert_array_equal(vk, cpu)
    assert vulkan.validation_errors == 0, vulkan.validation_messages()


def test_auto_range_and_scale_bar_are_the_palettes_colours():
    values = np.arange(W * H, dtype=np.float32).reshape(H, W) / 10
    image, (lo, hi) = counters.counter_image(values)
    assert (lo, hi) == (0.0, pytest.approx(np.percentile(values, counters.AUTO_PERCENTILE)))
    np.testing.assert_array_equal(image[:H], palette.heat_image(values, lo, hi))
    assert (image[:H][values >= hi][..., :3] == palette.heat([1.0])[0]).all()  # above the range: red
    bar = image[H + legend.MARGIN : H + legend.MARGIN + legend.BAR_HEIGHT, legend.MARGIN : W - legend.MARGIN, :3]
    inner = W - 2 * legend.MARGIN
    expected = palette.heat(np.linspace(0, 1, inner, dtype=np.float32))
    np.testing.assert_allclose(bar, np.broadcast_to(expected, bar.shape), atol=1e-6)
    assert (bar[:, 0] == palette.heat([0.0])[0]).all() and (bar[:, -1] == palette.heat([1.0])[0]).all()
    text = image[H + 2 * legend.MARGIN + legend.BAR_HEIGHT :, :, :3]
    assert (text == legend.TEXT_COLOR).all(-1).sum() == legend.text_mask("0").sum() + legend.text_mask(
        legend.number_text(hi)
    ).sum()  # the numbers of both ends, nothing else
    image, (lo, hi) = counters.counter_image(values, (10.0, 20.0))
    assert image[0, 0, :3].tolist() == palette.heat([0.0])[0].tolist() and (lo, hi) == (10.0, 20.0)
    with pytest.raises(ValueError, match="LO < HI"):
        counters.counter_image(values, (5.0, 5.0))
    assert counters.parse_range("auto") is None and counters.parse_range("1,9") == (1.0, 9.0)
    for bad in ("9,1", "1", "a,b", "1,inf"):
        with pytest.raises(ValueError):
            counters.parse_range(bad)


def test_difference_of_a_tree_with_itself_is_zero_and_median_against_sah_has_the_counters_sign():
    scene = bvhlab.Scene(triangles=procedural.torus_knot(4000))
    cpu = bvhlab.Renderer("cpu")
    sah = bvhlab.build(scene, method="sah", max_leaf_size=1)
    same = counter_difference(scene, sah, sah, "box_tests", W, H, renderer=cpu)
    assert (same["difference"] == 0).all() and same["span"] == 1.0
    assert (same["image"][:H, :, :3] == 1.0).all()  # white everywhere
    median = bvhlab.build(scene, method="median", max_leaf_size=1)
    for counter in ("box_tests", "prim_tests"):
        d = counter_difference(scene, median, sah, counter, W, H, renderer=cpu, labels=("median", "sah"))
        a, b = counter_planes(scene, (median, sah), counter, W, H, renderer=cpu)
        np.testing.assert_array_equal(d["difference"], a - b)
        assert (d["difference"] > 0).any() and (d["difference"] < 0).any(), "both signs to check"
        red, blue = d["difference"] > 0, d["difference"] < 0
        img = d["image"][:H, :, :3]
        assert (img[red][:, 0] > img[red][:, 2]).all() and (img[blue][:, 2] > img[blue][:, 0]).all()
        assert (img[d["difference"] == 0] == 1.0).all()
        np.testing.assert_array_equal(d["image"][:H], palette.diverging_image(d["difference"], d["span"]))
        lo, hi = s_range = d["summary"]["side_by_side_range"]
        assert s_range == list(counters.auto_range(np.concatenate([a.ravel(), b.ravel()])))
        pair = d["side_by_side"]  # first | gap | second, one range, one bar
        np.testing.assert_array_equal(pair[:H, :W], palette.heat_image(a, lo, hi))
        np.testing.assert_array_equal(pair[:H, -W:], palette.heat_image(b, lo, hi))
        assert pair.shape[1] == 2 * W + counter_diff.GAP and (pair[:H, W:-W, :3] == np.float32(legend.BACKGROUND)).all()
        s = d["summary"]
        assert s["median"]["mean"] == pytest.approx(a.mean()) and s["sah"]["mean"] == pytest.approx(b.mean())
        assert s["first_minus_second"]["mean"] == pytest.approx((a - b).mean(), abs=1e-5)
        assert s["pixels_first_more"] == int(red.sum())


def test_depth_legend_shows_each_depth_colour():
    strip = legend.depth_legend(120, range(2, 6))
    colours = palette.depth(np.arange(2, 6))
    swatch_row = strip[legend.MARGIN + 1, :, :3]
    for c in colours:
        assert (swatch_row == c).all(-1).sum() >= legend.TEXT_HEIGHT * 2
    other = palette.depth([7])[0]
    assert not (strip[..., :3] == other).all(-1).any()


def test_cli_render_counter_writes_the_image_and_the_counts(tmp_path, capsys):
    import sys

    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from png_reader import read_png

    from bvhlab.cli import main
    from bvhlab.png import linear_to_srgb

    out = tmp_path / "prim.png"
    args = ["render", "gen:whitted", "--width", str(W), "--height", str(H), "--backend", "cpu", "--out", str(out)]
    assert main([*args, "--counter", "prim_tests", "--range", "0,8"]) == 0
    counts = np.load(out.with_suffix(".npy"))
    scene, _ = bvhlab.library.load_scene("gen:whitted")
    expected = _counters(scene, bvhlab.build(scene)).counters[..., counters.counter_index("prim_tests")]
    np.testing.assert_array_equal(counts, expected)
    png = read_png(out)[..., :3].astype(int)
    want = (linear_to_srgb(palette.heat_image(counts, 0, 8)[..., :3]) * 255 + 0.5).astype(int)
    assert np.abs(png[:H] - want).max() <= 1
    assert "colour range 0..8 (given)" in capsys.readouterr().out
    assert main([*args, "--heatmap"]) == 0  # the old flag: box tests, auto range
    assert "auto: 0 to the 99th percentile" in capsys.readouterr().out
    for bad in (["--range", "3,1", "--counter", "box_hits"], ["--counter", "boxes"]):
        with pytest.raises(SystemExit) as e:
            main([*args, *bad])
        assert e.value.code == 2
    assert main([*args, "--range", "0,4"]) == 2  # a range without a counter
    assert "--range needs --counter" in capsys.readouterr().err


def test_cli_compare_counter_diff(tmp_path, capsys):
    import json

    from bvhlab.cli import main

    out = tmp_path / "diff"
    argv = ["compare", "gen:whitted", "--counter-diff", "median,sah12", "--counter", "box_tests"]
    assert main([*argv, "--width", "32", "--height", "24", "--backend", "cpu", "--out", str(out)]) == 0
    stem = out / "counter_diff_box_tests_median_sah12"
    a, b, d = np.load(stem.with_suffix(".npy"))
    np.testing.assert_array_equal(d, a - b)
    summary = json.loads(stem.with_suffix(".json").read_text())
    assert summary["median"]["mean"] == pytest.approx(float(a.mean()))
    said = capsys.readouterr()
    assert stem.with_suffix(".png").exists() and "median - sah12" in said.out
    assert (out / f"{stem.name}_side_by_side.png").exists()
    # the comparison's options are refused beside it (they were accepted and ignored)
    # the figures' folder named where they went (it named the staging folder, gone by then)
    assert f"wrote {stem.with_suffix('.png')}," in said.err
    for extra in (["--frames", "6"], ["--methods", "median"], ["--no-figures"], ["--threads", "2"], ["--threads", "0"]):
        assert main([*argv, *extra, "--out", str(tmp_path / "other")]) == 2
        assert f"{extra[0]} is an option of the comparison" in capsys.readouterr().err
