"""The render API a render engine builds on (issue 12): sample passes with progress and cancel, a
camera given directly, the Depth and cost outputs beside Combined; checked against the CPU
reference and against rays traced independently (Bvh.intersect)."""

import numpy as np
import pytest

import bvhlab
from bvhlab import _core
from bvhlab.library import procedural, showcase


@pytest.fixture(scope="module", params=["cpu", "vulkan"])
def renderer(request):
    r = bvhlab.Renderer(request.param, validation=request.param == "vulkan")
    yield r
    assert r.validation_errors == 0, r.validation_messages()


def test_sample_passes_refine_to_the_whole_render(renderer):
    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    whole, _ = renderer.render(scene, bvh, 48, 32, samples_per_axis=3)
    job = renderer.start(scene, bvh, 48, 32, samples_per_axis=3)
    assert (job.samples_done, job.samples_per_pixel) == (0, 9)
    coarse = job.result()
    assert np.all(coarse.color == 0) and np.all(coarse.depth == _core.NO_DEPTH), "nothing traced yet"
    job.run(1)
    first = job.result()
    assert first.samples == 1 and np.all(first.color[..., 3] == 1)
    assert np.abs(first.color - whole).mean() < 0.05, "a coarse image of the same scene"
    job.run(4)
    job.run()
    assert job.done and job.samples_done == 9
    np.testing.assert_array_equal(job.result().color, whole)  # passes sum exactly what one run sums


def test_progress_is_reported_and_false_cancels_then_the_job_goes_on(renderer):
    scene = showcase.five_spheres()
    bvh = bvhlab.build(scene)
    whole, _ = renderer.render(scene, bvh, 32, 24, samples_per_axis=2)
    seen = []
    job = renderer.start(scene, bvh, 32, 24, samples_per_axis=2)
    job.run(progress=seen.append)  # None means go on
    assert seen[-1] == 1.0 and all(0 <= f <= 1 for f in seen) and seen == sorted(seen)
    job = renderer.start(scene, bvh, 32, 24, samples_per_axis=2, steps_per_dispatch=16)
    with pytest.raises(bvhlab.RenderCancelled):
        job.run(progress=lambda f: False)
    assert job.samples_done == 0  # the check runs before any pixel or dispatch, whatever the threads do
    job.run()
    np.testing.assert_array_equal(job.result().color, whole)


def test_a_stop_answered_to_the_last_report_keeps_the_finished_render(renderer):
    """The CPU reference reports 1.0 when every sample is traced: a False then raised
    RenderCancelled ("at 16 of 16 samples") and render() lost the finished image (an audit)."""
    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    whole, _ = renderer.render(scene, bvh, 48, 32, samples_per_axis=4)
    job = renderer.start(scene, bvh, 48, 32, samples_per_axis=4)
    seen: list[float] = []
    job.run(progress=lambda f: seen.append(f) or f < 1.0)  # stop, once all is done
    assert seen[-1] == 1.0 and job.done
    np.testing.assert_array_equal(job.result().color, whole)
    image, _ = renderer.render(scene, bvh, 48, 32, samples_per_axis=4, progress=lambda f: f < 1.0)
    np.testing.assert_array_equal(image, whole)


def test_an_exception_in_progress_propagates_as_itself(renderer):
    scene = showcase.five_spheres()
    job = renderer.start(scene, bvhlab.build(scene), 16, 12)

    def boom(fraction):
        raise ZeroDivisionError("from the callback")

    with pytest.raises(ZeroDivisionError, match="from the callback"):
        job.run(progress=boom)
    with pytest.raises(ValueError, match="ambiguous"):  # numpy's own error, not a crash
        job.run(progress=lambda f: np.array([1, 2]))


def primary_depth(scene, bvh, view, width, height):
    """View-axis depth of the ray through each pixel centre, traced by Bvh.intersect (numpy camera)."""
    fwd = np.array(view.forward, np.float64) / np.linalg.norm(view.forward)
    right = np.cross(fwd, view.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    tan = np.tan(np.radians(view.fov_y) / 2)
    aspect = view.aspect or width / height
    larger = 2 * tan * max(aspect, 1.0)
    ys, xs = np.mgrid[0:height, 0:width] + 0.5
    x = (xs / width * 2 - 1) * tan * aspect + view.shift_x * larger
    y = (1 - ys / height * 2) * tan + view.shift_y * larger
    d = fwd + x[..., None] * right + y[..., None] * up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    origins = np.tile(np.float32(view.position), (width * height, 1))
    hits = bvh.intersect(origins, np.float32(d.reshape(-1, 3)))
    t = hits["t"].reshape(height, width).astype(np.float64)
    return np.where(np.isinf(t), _core.NO_DEPTH, t * (d @ fwd))


def test_view_camera_depth_and_cost(renderer):
    """A camera given as position, forward, up, fov, aspect and lens shift: its Depth is the view-axis
    distance of what each pixel shows (Blender's Z), 1e10 where nothing is hit."""
    scene = bvhlab.Scene(triangles=procedural.torus_knot(20000))
    bvh = bvhlab.build(scene)
    view = bvhlab.View(
        position=(0.4, -3.2, 1.1),
        forward=(-0.1, 1.0, -0.3),
        up=(0, 0, 1),
        fov_y=40,
        aspect=1.6,
        shift_x=0.05,
        shift_y=-0.08,
    )
    w, h = 64, 40
    result = renderer.start(scene, bvh, w, h, camera=view, max_depth=0)
    result.run()
    out = result.result()
    expected = primary_depth(scene, bvh, view, w, h)
    hit = expected < _core.NO_DEPTH
    assert 0.1 < hit.mean() < 0.9, "the test's geometry: some knot, some sky"
    close = np.isclose(out.depth, expected, rtol=1e-4) | (out.depth == expected)
    assert close.mean() >= 0.99, "at most a pixel in a hundred on a grazing edge"
    assert np.all(out.cost > 0) and np.all(out.cost[hit] >= 1)
    reference = bvhlab.Renderer("cpu").start(scene, bvh, w, h, camera=view, max_depth=0)
    reference.run()
    ref = reference.result()
    np.testing.assert_allclose(out.depth, ref.depth, rtol=1e-5)
    np.testing.assert_array_equal(out.cost, ref.cost)


def test_view_equals_the_look_at_camera():
    scene = showcase.five_spheres()
    bvh = bvhlab.build(scene)
    camera = bvhlab.Camera((1, -8, 3), (0, 0, 1), fov_y=50)
    a, _ = bvhlab.render(scene, bvh, 40, 30, backend="cpu", camera=camera)
    b, _ = bvhlab.render(scene, bvh, 40, 30, backend="cpu", camera=bvhlab.View((1, -8, 3), (-1, 8, -2), fov_y=50))
    np.testing.assert_array_equal(a, b)
    # the picture shows the spheres and the sky: two images of nothing would be equal too
    job = bvhlab.Renderer("cpu").start(scene, bvh, 40, 30, camera=camera, max_depth=0)
    job.run()
    hit = job.result().depth < _core.NO_DEPTH
    assert 0.05 < hit.mean() < 0.95, hit.mean()


def test_cost_is_what_the_heatmap_colours():
    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    job = bvhlab.Renderer("cpu").start(scene, bvh, 32, 24, samples_per_axis=2, mode="heatmap", heatmap_scale=40.0)
    job.run()
    out = job.result()
    x = np.clip(out.cost.reshape(-1).astype(np.float64) / 40.0, 0, 1)
    # the ramp as documented (blue 0 -> cyan -> green -> yellow -> red 1), written out here
    ramp = np.clip(1.5 - np.abs(4 * x[:, None] - np.array([3.0, 2.0, 1.0])), 0, 1)
    np.testing.assert_allclose(out.color[..., :3].reshape(-1, 3), ramp, atol=1e-5)
    np.testing.assert_allclose(_core.heat_colors(np.float32([0, 0.5, 1])), [[0, 0, 0.5], [0.5, 1, 0.5], [0.5, 0, 0]])
    assert np.all(out.cost >= 1) and out.cost.max() > 2 * out.cost.min(), "costs that differ from pixel to pixel"


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        (dict(overlay_depth=5), TypeError, "overlay_depth must be a pair"),
        (dict(heatmap_scale="x"), TypeError, "heatmap_scale must be a number"),
        (dict(camera=(0, 0, 0)), TypeError, "camera must be a bvhlab.Camera or bvhlab.View"),
        (dict(traversal=3), TypeError, "traversal must be a string"),
    ],
)
def test_clear_errors(kwargs, error, match):
    scene = showcase.five_spheres()
    with pytest.raises(error, match=match):
        bvhlab.render(scene, bvhlab.build(scene), 16, 12, backend="cpu", **kwargs)


@pytest.mark.parametrize(
    "args, kwargs, match",
    [
        (((0, 0, 0), (0, 0, 0)), {}, "view direction is zero"),
        (((0, 0, 0), (0, 0, 1)), dict(up=(0, 0, 2)), "parallel"),
        (((0, 0, 0), (0, 1, 0)), dict(projection="orthographic"), "needs ortho_scale"),
        (((0, 0, 0), (0, 1, 0)), dict(clip_start=2.0, clip_end=1.0), "clip_start < clip_end"),
        (((0, 0, 0), (0, 1, 0)), dict(region=(0.5, 0, 0.5, 1)), "camera region"),
        (((0, 0, 0), (0, 1, 0)), dict(projection="cylindrical"), "unknown projection 'cylindrical'"),
        (((0, 0, 0), (0, 1, 0)), dict(fov_y=float("nan")), "NaN"),
    ],
)
def test_a_bad_view_is_refused_when_made(args, kwargs, match):
    with pytest.raises(ValueError, match=match):
        bvhlab.View(*args, **kwargs)


def test_huge_render_is_refused_before_any_allocation():
    scene = showcase.five_spheres()
    with pytest.raises(ValueError, match="exceeds the device limit of 16384"):
        bvhlab.Renderer("cpu").start(scene, bvhlab.build(scene), 100000, 100000)


def test_the_scene_cache_sees_in_place_edits():
    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    renderer = bvhlab.Renderer("cpu")
    before, _ = renderer.render(scene, bvh, 32, 24)
    scene.tri_material[:] = 0  # the floor's checker → one material, edited in place
    after, _ = renderer.render(scene, bvh, 32, 24)
    assert not np.array_equal(before, after)
    scene.triangles[:, :, 2] += np.float32(0.5)  # moved in place: the tree no longer fits
    with pytest.raises(ValueError, match="other geometry"):
        renderer.render(scene, bvh, 32, 24)
    bvh.refit(scene.triangles, scene.spheres)
    moved, _ = renderer.render(scene, bvh, 32, 24)
    assert not np.array_equal(moved, after)
    np.testing.assert_array_equal(moved, bvhlab.Renderer("cpu").render(scene, bvh, 32, 24)[0])


def test_depth_order_one_convention():
    """The one depth order (core_cpp/src/tree/depth_order.cpp) behind Bvh.boxes and the overlay
    pass, exposed for the add-on: nodes by depth, [first, last) ranges."""
    bvh = bvhlab.build(procedural.random_triangles(500, seed=4))
    nodes, offset = bvh._core.depth_order()
    depths = bvh.depths
    assert sorted(nodes.tolist()) == list(range(len(depths)))
    np.testing.assert_array_equal(depths[nodes], np.sort(depths, kind="stable"))
    assert offset[0] == 0 and offset[-1] == len(depths) and len(offset) == bvh.stats["height"] + 1
    for lo, hi in [(0, 0), (2, 5), (3, 200), (9, 2)]:
        first, last = bvh._core.depth_range(lo, hi)
        assert last - first == len(bvh.boxes(lo, hi)[2]) if lo <= hi else (first, last) == (0, 0)
        assert np.all((depths[nodes[first:last]] >= lo) & (depths[nodes[first:last]] <= hi))


def test_a_pixel_that_cannot_finish_is_an_error(renderer):
    """Ten thousand copies of one triangle: a primary ray alone takes some 20,000 steps of work; with
    max_steps_per_pixel below that the render raises instead of returning an unfinished image."""
    one = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], np.float32)
    scene = bvhlab.Scene(
        triangles=np.ascontiguousarray(np.repeat(one, 10000, 0)),
        camera=bvhlab.Camera((0.3, 0.3, 2), (0.3, 0.3, 0), up=(0, 1, 0), fov_y=30),
    )
    bvh = bvhlab.build(scene)
    with pytest.raises(
        bvhlab.RenderIncomplete, match=r"^at least \d+ pixel\(s\) did not finish within 5000 .* stops at the first"
    ):
        renderer.render(scene, bvh, 8, 8, max_steps_per_pixel=5000)
    image, _ = renderer.render(scene, bvh, 8, 8)  # with the default cap it finishes
    assert np.all(image[..., 3] == 1)


def test_an_image_size_below_one_is_refused_in_one_voice():
    """Width -1 said "between 0 and 2147483648" and 0 "at least 1" (helper probe)."""
    scene = bvhlab.Scene(triangles=np.random.default_rng(0).random((20, 3, 3), dtype=np.float32))
    bvh = bvhlab.build(scene)
    for width, height, name in ((-1, 5, "width"), (0, 5, "width"), (5, 0, "height"), (5, -3, "height")):
        with pytest.raises(ValueError, match=f"{name} must be between 1 and 2147483648, got {min(width, height)}"):
            bvhlab.render(scene, bvh, width, height, backend="cpu")
