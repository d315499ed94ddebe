"""The cameras of the tracer (issue 33; core_cpp/include/bvhlab/camera.h): each projection's Depth
against rays worked out here in numpy from the documented conventions and traced by Bvh.intersect
(another traversal and ray test), on the CPU reference and Vulkan; the Vulkan image against the CPU
reference's; a region of the frame equals that part of the whole frame; clipping; depth of field in
focus; denormal camera vectors (issue 39 #7); a lens saved in a scene file."""

import math
from dataclasses import replace

import numpy as np
import pytest

import bvhlab
from bvhlab import _core
from bvhlab.library import procedural, showcase

MISS = _core.NO_DEPTH


@pytest.fixture(scope="module", params=["cpu", "vulkan"])
def renderer(request):
    r = bvhlab.Renderer(request.param, validation=request.param == "vulkan")
    yield r
    assert r.validation_errors == 0, r.validation_messages()


@pytest.fixture(scope="module")
def knot():
    scene = bvhlab.Scene(triangles=procedural.torus_knot(20000))
    return scene, bvhlab.build(scene)


def depth_of(renderer, scene, bvh, view, width, height, **options):
    job = renderer.start(scene, bvh, width, height, camera=view, max_depth=0, **options)
    job.run()
    return job.result(color=False, cost=False).depth


def basis(view):
    forward = np.array(view.forward, np.float64) / np.linalg.norm(view.forward)
    right = np.cross(forward, view.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return forward, -right if view.mirrored else right, up


def pixel_rays(view, width, height):
    """(origins, unit directions, depth per unit t) of the rays through the pixel centres, row 0 at
    the top, from the View's documented conventions (Lens's docstring; Cycles' projection.h for
    the panoramas: longitude across from the left, latitude up; fisheye angle ∝ radius)."""
    forward, right, up = basis(view)
    x0, y0, x1, y1 = view.region
    u = x0 + (np.arange(width) + 0.5) / width * (x1 - x0)  # across the frame, 0 at its left
    v = 1 - (y0 + (np.arange(height) + 0.5) / height * (y1 - y0))  # up the frame, 0 at its bottom
    u, v = np.meshgrid(u, v)
    origins = np.broadcast_to(np.array(view.position, np.float64), u.shape + (3,)).copy()
    aspect = view.aspect or (width / (x1 - x0)) / (height / (y1 - y0))
    if view.projection in ("perspective", "orthographic"):
        if view.projection == "perspective":
            plane_h = 2 * math.tan(math.radians(view.fov_y) / 2)
            larger = plane_h * max(aspect, 1)
        else:
            larger = view.ortho_scale
            plane_h = larger / aspect if aspect >= 1 else larger
        x = (u - 0.5) * plane_h * aspect + view.shift_x * larger
        y = (v - 0.5) * plane_h + view.shift_y * larger
        offset = x[..., None] * right + y[..., None] * up
        if view.projection == "perspective":
            d = forward + offset
        else:
            origins += offset
            d = np.broadcast_to(forward, offset.shape).copy()
    elif view.projection == "equirectangular":
        (lat0, lat1), (lon0, lon1) = np.radians(view.latitude), np.radians(view.longitude)
        longitude = lon0 + (u + view.shift_x) * (lon1 - lon0)  # to the right
        latitude = lat0 + (v + view.shift_y) * (lat1 - lat0)
        d = (
            np.cos(latitude)[..., None]
            * (np.cos(longitude)[..., None] * forward + np.sin(longitude)[..., None] * right)
            + np.sin(latitude)[..., None] * up
        )
    else:  # fisheye equidistant over the frame's ellipse
        a, b = 2 * (u + view.shift_x) - 1, 2 * (v + view.shift_y) - 1
        r = np.hypot(a, b)
        theta = r * math.radians(view.fisheye_fov) / 2
        s = np.where(r > 0, np.sin(theta) / np.maximum(r, 1e-30), 0)
        d = np.cos(theta)[..., None] * forward + (a * s)[..., None] * right + (b * s)[..., None] * up
        d[r > 1] = np.nan  # no ray
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    per_t = 1.0 if view.projection in ("equirectangular", "fisheye") else d @ forward
    return origins, d, per_t


def expected_depth(bvh, view, width, height):
    """The nearest surface beyond the near clipping plane (the rays start on it, as Cycles starts
    them), if it lies before the far one."""
    origins, d, per_t = pixel_rays(view, width, height)
    origins = origins + d * (view.clip_start / np.asarray(per_t))[..., None]
    valid = np.isfinite(d).all(-1)
    t = np.full(valid.shape, np.inf)
    hits = bvh.intersect(np.float32(origins[valid]), np.float32(d[valid]))
    t[valid] = hits["t"]
    depth = view.clip_start + t * per_t
    return np.where(np.isfinite(depth) & (depth <= view.clip_end), depth, MISS)


VIEWS = {
    "perspective": bvhlab.View((0.4, -3.2, 1.1), (-0.1, 1.0, -0.3), fov_y=40, aspect=1.6, shift_x=0.05),
    "orthographic": bvhlab.View(
        (0.3, -4.0, 0.9), (-0.05, 1.0, -0.2), projection="orthographic", ortho_scale=3.0, shift_y=0.1
    ),
    "orthographic_portrait": bvhlab.View(
        (0.3, -4.0, 0.9), (0.0, 1.0, 0.0), projection="orthographic", ortho_scale=3.0, aspect=0.6
    ),
    "equirectangular": bvhlab.View(
        (0.0, -1.5, 0.2), (0.2, 1.0, 0.0), projection="equirectangular", latitude=(-50, 70), longitude=(-100, 140)
    ),
    "fisheye": bvhlab.View((0.0, -2.5, 0.2), (0.0, 1.0, 0.1), projection="fisheye", fisheye_fov=150, shift_x=0.05),
    # what Blender's settings take and Cycles renders: ranges from max to min (mirrored), longitudes
    # past ±180 (wrapped), a fisheye past 360 degrees
    "equirectangular_inverted": bvhlab.View(
        (0.0, -1.5, 0.2), (0.2, 1.0, 0.0), projection="equirectangular", latitude=(70, -50), longitude=(140, -100)
    ),
    "equirectangular_wrapped": bvhlab.View(
        (0.0, -1.5, 0.2), (0.2, 1.0, 0.0), projection="equirectangular", longitude=(-300, 300)
    ),
    "fisheye_past_360": bvhlab.View((0.0, -2.5, 0.2), (0.0, 1.0, 0.1), projection="fisheye", fisheye_fov=400),
    "clipped": bvhlab.View((0.4, -3.2, 1.1), (-0.1, 1.0, -0.3), fov_y=40, clip_start=2.9, clip_end=3.3),
    "clipped_equirectangular": bvhlab.View(
        (0.0, -1.5, 0.2), (0.2, 1.0, 0.0), projection="equirectangular", clip_start=1.2, clip_end=1.8
    ),
    "region": bvhlab.View((0.4, -3.2, 1.1), (-0.1, 1.0, -0.3), fov_y=40, region=(0.2, 0.1, 0.7, 0.9)),
    # a Blender camera of negative determinant (a scale of -1): the image mirrored, its shift too
    "mirrored": bvhlab.View((0.4, -3.2, 1.1), (-0.1, 1.0, -0.3), fov_y=40, aspect=1.6, shift_x=0.15, mirrored=True),
    "mirrored_equirectangular": bvhlab.View(
        (0.0, -1.5, 0.2), (0.2, 1.0, 0.0), projection="equirectangular", longitude=(-100, 140), mirrored=True
    ),
}


@pytest.mark.parametrize("name", VIEWS)
def test_depth_is_the_rays_worked_out_here(renderer, knot, name):
    scene, bvh = knot
    view = VIEWS[name]
    w, h = 48, 32
    out = depth_of(renderer, scene, bvh, view, w, h)
    expected = expected_depth(bvh, view, w, h)
    hit = expected < MISS
    assert 0.05 < hit.mean() < 0.95, f"the test's geometry: some knot, some sky ({hit.mean():.2f})"
    close = np.isclose(out, expected, rtol=1e-4) | (out == expected)
    assert close.mean() >= 0.99, f"{name}: {close.mean():.4f} of the pixels agree (a grazing edge may differ)"


def test_a_region_is_that_part_of_the_whole_frame(renderer, knot):
    """The render border: an image of region (x0, y0, x1, y1) shows exactly those pixels of the
    whole frame (pixel edges on the region's edges)."""
    scene, bvh = knot
    view = VIEWS["perspective"]
    whole = depth_of(renderer, scene, bvh, view, 60, 40)
    part = depth_of(renderer, scene, bvh, replace(view, region=(12 / 60, 8 / 40, 42 / 60, 32 / 40)), 30, 24)
    np.testing.assert_allclose(part, whole[8:32, 12:42], rtol=1e-5)


def _both(scene, bvh, view, backends, **options):
    out = []
    for r in backends:
        job = r.start(scene, bvh, 40, 30, camera=view, samples_per_axis=2, **options)
        job.run()
        out.append(job.result())
    return out


def test_vulkan_equals_the_cpu_reference_for_every_camera():
    """Colour, depth and cost of every projection, with supersampling, reflections and depth of
    field: the Vulkan image equals the CPU reference's (the same tracer code; lavapipe may fuse a
    multiply-add). The box overlay (perspective, orthographic) is rasterized by the GPU's line
    rules there and a DDA on the CPU: the lines' pixels overlap, the rest is equal."""
    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    backends = bvhlab.Renderer("cpu"), bvhlab.Renderer("vulkan", validation=True)
    thin_lens = dict(aperture_radius=0.1, focus_distance=5.0)
    ortho = dict(projection="orthographic", ortho_scale=5.3)
    # a view askew to the boxes for the overlay: edges on pixel boundaries are the rasterizers' ties
    askew = (0.3, -6.0, 1.2), (-0.13, 1.0, -0.11)
    cases = [
        (bvhlab.View(*askew, **ortho, shift_x=0.1), (1, 3)),
        (bvhlab.View(*askew, **thin_lens), (2, 4)),
        (bvhlab.View((0, -6, 1), (0, 1, 0), **ortho, **thin_lens), None),
        (bvhlab.View((0, -6, 1), (0, 1, 0), projection="equirectangular", **thin_lens), None),
        (bvhlab.View((0, -6, 1), (0, 1, 0), projection="fisheye", fisheye_fov=220), None),
        (bvhlab.View(*askew, clip_start=4.0, clip_end=12.0, region=(0.1, 0.2, 0.8, 0.7)), (1, 2)),
    ]
    try:
        for view, overlay in cases:
            cpu, vulkan = _both(scene, bvh, view, backends, overlay_depth=overlay)
            lines = np.zeros(cpu.depth.shape, bool)
            if overlay is not None:
                plain = _both(scene, bvh, view, backends)
                on_cpu, on_vulkan = (np.any(a.color != b.color, -1) for a, b in zip((cpu, vulkan), plain))
                overlap = (on_cpu & on_vulkan).sum() / (on_cpu | on_vulkan).sum()
                assert on_cpu.sum() > 20 and overlap > 0.85, (view, on_cpu.sum(), overlap)
                lines = on_cpu | on_vulkan
            assert np.abs(cpu.color - vulkan.color)[~lines].max() < 1e-5, view
            np.testing.assert_allclose(vulkan.depth[~lines], cpu.depth[~lines], rtol=1e-5)
            np.testing.assert_array_equal(vulkan.cost[~lines], cpu.cost[~lines])  # a line caps the walk
    finally:
        assert backends[1].validation_errors == 0, backends[1].validation_messages()


def test_clipping_keeps_only_what_lies_between_the_planes(renderer, knot):
    scene, bvh = knot
    view = VIEWS["clipped"]
    out = depth_of(renderer, scene, bvh, view, 48, 32)
    hit = out < MISS
    assert hit.any() and np.all((out[hit] > view.clip_start) & (out[hit] <= view.clip_end * (1 + 1e-6)))
    unclipped = depth_of(renderer, scene, bvh, replace(view, clip_start=0.0, clip_end=math.inf), 48, 32)
    assert (unclipped < MISS).sum() > hit.sum(), "the planes must cut something off"


def test_depth_of_field_keeps_the_focus_plane_sharp(renderer):
    """A wall facing the camera at the focus distance: every sample through the thin lens meets it
    where the pinhole ray does, so its depth is the same with and without depth of field."""
    quad = np.array([[[-3, 4, -3], [3, 4, -3], [3, 4, 3]], [[-3, 4, -3], [3, 4, 3], [-3, 4, 3]]], np.float32)
    scene = bvhlab.Scene(triangles=quad)
    bvh = bvhlab.build(scene)
    pinhole = bvhlab.View((0, 0, 0), (0, 1, 0), fov_y=50)
    focused = bvhlab.View((0, 0, 0), (0, 1, 0), fov_y=50, aperture_radius=0.3, focus_distance=4.0)
    a = depth_of(renderer, scene, bvh, pinhole, 24, 18, samples_per_axis=3)
    b = depth_of(renderer, scene, bvh, focused, 24, 18, samples_per_axis=3)
    np.testing.assert_allclose(b, a, rtol=1e-5)
    assert np.all(a < MISS)


@pytest.mark.parametrize(
    "kwargs",
    [dict(forward=(0.0, 1e-40, 0.0)), dict(forward=(0.0, 1.0, 0.0), up=(0.0, 0.0, 1e-40))],
)
def test_denormal_camera_vectors_render_the_scene(renderer, kwargs):
    """Issue 39 #7: a view direction or up vector of denormal floats (1e-40) is a direction like any
    other: the same picture as the unit vector's (it rendered a uniform sky: the rescale overflowed)."""
    scene = showcase.five_spheres()
    bvh = bvhlab.build(scene)
    unit = bvhlab.View((0.0, -8.0, 1.0), (0.0, 1.0, 0.0))
    denormal = bvhlab.View((0.0, -8.0, 1.0), **{"up": (0.0, 0.0, 1.0), **kwargs})
    a = depth_of(renderer, scene, bvh, unit, 32, 24)
    b = depth_of(renderer, scene, bvh, denormal, 32, 24)
    assert (a < MISS).mean() > 0.1
    np.testing.assert_array_equal(a, b)


def test_a_vector_that_is_zero_in_float32_is_refused():
    with pytest.raises(ValueError, match="view direction is zero"):
        bvhlab.View((0.0, -8.0, 1.0), (0.0, 1e-46, 0.0))


def test_a_camera_lens_is_saved_and_loaded(tmp_path):
    scene = showcase.five_spheres()
    scene.camera = bvhlab.Camera(
        (1.0, -8.0, 2.0),
        (0.0, 0.0, 0.5),
        projection="orthographic",
        ortho_scale=7.5,
        aspect=1.25,
        shift_x=0.1,
        clip_start=0.5,
        clip_end=40.0,
        aperture_radius=0.02,
        focus_distance=6.0,
    )
    path = scene.save(tmp_path / "lens.npz")
    assert bvhlab.Scene.load(path).camera == scene.camera
    scene.camera = bvhlab.Camera((1.0, -8.0, 2.0), (0.0, 0.0, 0.5), projection="equirectangular", latitude=(-30, 60))
    assert bvhlab.Scene.load(scene.save(path)).camera == scene.camera
    scene.camera = bvhlab.Camera((1.0, -8.0, 2.0), (0.0, 0.0, 0.5), shift_x=0.1, mirrored=True)
    assert bvhlab.Scene.load(scene.save(path)).camera == scene.camera
    # a row written before `mirrored` (one number fewer) loads unmirrored
    row = scene.camera.as_row()[:-1]
    assert bvhlab.Camera.from_row(row) == replace(scene.camera, mirrored=False)
    with pytest.raises(ValueError, match="mirrored flag"):
        bvhlab.Camera.from_row(row + [0.5])
    with pytest.raises(TypeError, match="mirrored must be True or False"):
        bvhlab.View((0, 0, 0), (0, 1, 0), mirrored="yes")


def test_the_overlay_needs_straight_lines():
    scene = showcase.five_spheres()
    view = bvhlab.View((0.0, -8.0, 1.0), (0.0, 1.0, 0.0), projection="fisheye")
    with pytest.raises(ValueError, match="perspective or orthographic camera"):
        bvhlab.render(scene, bvhlab.build(scene), 16, 12, backend="cpu", camera=view, overlay_depth=(0, 2))


def test_a_fisheyes_corners_are_opaque_black_with_film_transparent(renderer):
    """Outside the fisheye's ellipse there is no camera ray: Cycles writes opaque black there with
    Film ▸ Transparent (a probe: bvhlab wrote alpha 0); the sky inside stays transparent."""
    scene = showcase.five_spheres()
    view = bvhlab.View((0, -8, 1), (0, 1, 0), projection="fisheye", fisheye_fov=120)
    job = renderer.start(scene, bvhlab.build(scene), 40, 30, camera=view, film_transparent=True)
    job.run()
    color = job.result().color
    for corner in (color[0, 0], color[0, -1], color[-1, 0], color[-1, -1]):
        assert corner.tolist() == [0.0, 0.0, 0.0, 1.0]
    inside_sky = color[15, :, 3] == 0
    assert inside_sky.any(), "the test's view: some sky inside the ellipse"
