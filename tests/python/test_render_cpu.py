"""The tracer's algorithm, checked on the CPU reference against geometry and optics computed here
independently: shadow transmission, Snell refraction, the sky (the overlay's lines:
test_render_cpu_overlay.py)."""

import math

import numpy as np
import pytest
from oracles import camera_ray_hits

import bvhlab
from bvhlab.library import showcase
from bvhlab.render import _core

SKY = (0.25, 0.5, 0.75)


def project(camera: bvhlab.Camera, width: int, height: int, point) -> tuple[float, float]:
    """Image position (x right, y down, in pixels) of a world point under the tracer's camera."""
    pos, look, up = (np.array(v, np.float64) for v in (camera.position, camera.look_at, camera.up))
    fwd = (look - pos) / np.linalg.norm(look - pos)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, fwd)
    v = np.array(point, np.float64) - pos
    tan = math.tan(math.radians(camera.fov_y) / 2)
    x = v @ right / (v @ fwd) / (tan * width / height)
    y = v @ true_up / (v @ fwd) / tan
    return (x + 1) / 2 * width, (1 - y) / 2 * height


def render(scene, width=96, height=64, **kw):
    image, _ = bvhlab.render(scene, bvhlab.build(scene), width, height, backend="cpu", **kw)
    return image


def test_sky_where_nothing_is_hit():
    scene = showcase.five_spheres()
    scene.sky = SKY
    image = render(scene)
    np.testing.assert_array_equal(image[0, 0], [*np.float32(SKY), 1.0])  # the top-left corner is sky
    assert np.any(np.abs(image[..., :3] - np.float32(SKY)).sum(-1) > 0.1), "and the spheres are not"


def test_empty_scene_renders_sky_only():
    scene = bvhlab.Scene(camera=bvhlab.Camera((0, -5, 1), (0, 0, 0)), sky=SKY)
    image = render(scene, 16, 8)
    assert np.all(image[..., :3] == np.float32(SKY)) and np.all(image[..., 3] == 1)


def shadow_scene(transparent: float | None):
    """A floor, a sphere above it (or none), a light off to the side."""
    floor = showcase.quad((-10, -10, 0), (10, -10, 0), (10, 10, 0), (-10, 10, 0))
    spheres = np.zeros((0, 4), np.float32) if transparent is None else np.array([[0, 0, 1.5, 0.5]], np.float32)
    return bvhlab.Scene(
        triangles=floor,
        spheres=spheres,
        materials=[bvhlab.Material((0.8, 0.8, 0.8)), bvhlab.Material((0.3, 0.9, 0.3), transparent=transparent or 0.0)],
        tri_material=[0, 0],
        sphere_material=[1] * len(spheres),
        camera=bvhlab.Camera((0, -8, 6), (0, 0, 0.5)),
        light=bvhlab.Light((2, 0, 4.5)),
    )


@pytest.mark.parametrize("transparent", [0.5, 0.3])
def test_transparent_shadow_is_lighter_by_the_product_of_transparencies(transparent):
    # The shadow centre: the floor point on the line from the light through the sphere's centre.
    light, center = np.array([2, 0, 4.5]), np.array([0, 0, 1.5])
    d = center - light
    shadow = light + d * (light[2] / -d[2])
    camera = shadow_scene(None).camera
    x, y = project(camera, 96, 64, shadow)
    px = int(x), int(y)
    lit = render(shadow_scene(None))[px[1], px[0], :3]
    dark = render(shadow_scene(0.0))[px[1], px[0], :3]
    half = render(shadow_scene(transparent))[px[1], px[0], :3]
    assert np.all(dark < lit - 0.1), "the opaque sphere casts a shadow there"
    # The shadow ray crosses the sphere's surface twice: transmission = transparent².
    np.testing.assert_allclose((half - dark) / (lit - dark), transparent**2, rtol=1e-3)


def slab_scene(ior: float, with_slab: bool = True):
    """A red | green wall (boundary at x = 0), a glass slab tilted 35° about z in front of it."""
    wall_red = showcase.quad((-20, 6, -10), (0, 6, -10), (0, 6, 10), (-20, 6, 10))
    wall_green = showcase.quad((0, 6, -10), (20, 6, -10), (20, 6, 10), (0, 6, 10))
    tris, mats = [wall_red, wall_green], [0, 0, 1, 1]
    if with_slab:
        slab = showcase.box_mesh((-3, -1, -3), (3, 1, 3)).astype(np.float64)
        a = math.radians(35)
        rot = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
        tris.append((slab @ rot.T).astype(np.float32))
        mats += [2] * 12
    return bvhlab.Scene(
        triangles=np.concatenate(tris),
        tri_material=np.array(mats),
        materials=[
            bvhlab.Material((1, 0, 0)),
            bvhlab.Material((0, 1, 0)),
            bvhlab.Material((1, 1, 1), transparent=1.0, ior=ior),
        ],
        camera=bvhlab.Camera((0, -6, 0), (0, 0, 0), fov_y=20),
        light=bvhlab.Light((0, -5, 0)),
    )


def boundary_column(image) -> float:
    """Where the wall turns from red to green along the middle row, in pixels, to a fraction of a
    pixel: the boundary pixel's share of green samples places it inside the pixel."""
    row = image[image.shape[0] // 2, :, :3].astype(np.float64)
    green = row[:, 1] / np.maximum(row[:, 0] + row[:, 1], 1e-9)
    w = len(green)
    k = w // 4 + int(np.argmax(green[w // 4 : 3 * w // 4] > 0.5))  # first mostly-green pixel
    g_red, g_green = green[k - 3], green[k + 3]
    covered = np.clip((green[k - 1] - g_red) / (g_green - g_red), 0, 1)  # green share of pixel k-1
    return k - covered


def snell_boundary_column(ior: float, width: int) -> float:
    """Independent optics: the image column whose centre ray, refracted through the tilted slab,
    lands on x = 0 of the wall (bisection on the column)."""
    cam = slab_scene(ior).camera
    a = math.radians(35)
    n = np.array([-math.sin(a), math.cos(a), 0.0])  # slab face normal (rotated +y)

    def wall_x(col: float) -> float:
        tan = math.tan(math.radians(cam.fov_y) / 2)
        d = np.array([(2 * col / width - 1) * tan * width / 64, 1.0, 0.0])
        d /= np.linalg.norm(d)
        p = np.array(cam.position, np.float64)
        for face, eta in ((-1.0, 1 / ior), (1.0, ior)):  # enter the front face, leave the back
            t = (face - p @ n) / (d @ n)
            p = p + t * d
            nn = n if d @ n < 0 else -n  # the normal facing the incoming ray
            k = 1 - eta**2 * (1 - (d @ nn) ** 2)
            d = eta * d - (eta * (d @ nn) + math.sqrt(k)) * nn
        t = (6 - p[1]) / d[1]
        return (p + t * d)[0]

    lo, hi = 0.0, float(width)
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if wall_x(mid) < 0 else (lo, mid)
    return lo


def test_refraction_through_a_slab_follows_snell():
    width = 200
    plain = boundary_column(render(slab_scene(1.0, with_slab=False), width, 64, samples_per_axis=4))
    assert plain == pytest.approx(width / 2, abs=0.1), "no slab: the boundary is straight ahead"
    same = boundary_column(render(slab_scene(1.0), width, 64, samples_per_axis=4))
    assert same == pytest.approx(plain, abs=0.1), "IOR 1.0: the ray passes straight"
    bent = boundary_column(render(slab_scene(1.5), width, 64, samples_per_axis=4))
    expected = snell_boundary_column(1.5, width)
    assert abs(expected - plain) > 5, "the test geometry must displace the ray visibly"
    assert bent == pytest.approx(expected, abs=0.3)


@pytest.mark.parametrize(
    "make, build, shape",
    [
        (showcase.whitted, {"method": "mean"}, {}),
        # leaves of up to 8, pushed and popped as the farther child
        (showcase.whitted, {"method": "mean", "max_leaf_size": 8}, {"max_leaf_size": 8}),
        (showcase.five_spheres, {"method": "median", "max_leaf_size": 8}, {"nodes": 1}),  # a root leaf: no pairs
        (showcase.five_spheres, {"method": "median", "max_leaf_size": 1}, {"max_leaf_size": 1}),
    ],
    ids=["whitted_mean", "whitted_leaf8", "root_leaf", "five_spheres_leaf1"],
)
def test_stack_stackless_and_wide_images_are_identical(make, build, shape):
    """The stack walk reads the internal nodes as pairs of child boxes, the stackless one the
    depth-first nodes, the wide one the tree's 8-wide copy (the CPU queries' walk): three layouts of
    one tree, so the same closest hits and the same image, bit for bit."""
    scene = make()
    bvh = bvhlab.build(scene, **build)
    for key, value in shape.items():  # the tree has the shape the case is for
        assert bvh.stats[key] == value, key
    kw = dict(backend="cpu", samples_per_axis=2, max_depth=4)
    a, _ = bvhlab.render(scene, bvh, 64, 48, traversal="stack", **kw)
    b, _ = bvhlab.render(scene, bvh, 64, 48, traversal="stackless", **kw)
    np.testing.assert_array_equal(a, b)
    c, t = bvhlab.render(scene, bvh, 64, 48, traversal="wide", **kw)
    np.testing.assert_array_equal(a, c)
    assert "wide walk" in t["device"]
    sky = np.all(np.abs(a[..., :3] - np.array(scene.sky, np.float32)) < 1e-6, -1)
    assert 0.05 < sky.mean() < 0.95  # geometry and sky both in view


def _job(scene, bvh, **options):
    job = bvhlab.Renderer("cpu").start(scene, bvh, 64, 48, samples_per_axis=2, max_depth=4, **options)
    job.run()
    return job.result(heat=True, counters=bool(options.get("traversal_counters")))


def test_auto_traversal_is_the_wide_walk_on_the_cpu_and_the_stack_walk_where_counts_show():
    """Traversal "auto" (the add-on's and the render CLI's default) on the CPU: the wide walk where
    the image shows no count of the walk (its image and cost are the wide walk's, the image the
    stack walk's); in mode "heatmap" and with traversal counters the stack walk, whose counts are
    the binary tree's box tests (its heat and counters equal the stack walk's, not the wide one's)."""
    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    stack, wide, auto = (_job(scene, bvh, traversal=t) for t in ("stack", "wide", "auto"))
    assert auto.timings["traversal"] == "wide" and "wide walk" in auto.timings["device"]
    # whitted's glass: the wide walk answered the shadow rays blocked by an opaque surface first
    assert auto.timings["shadow_rays_opaque"] > 0 and auto.timings["shadow_rays_glass"] > 0
    assert stack.timings["shadow_rays_opaque"] == stack.timings["shadow_rays_glass"] == 0
    np.testing.assert_array_equal(auto.color, stack.color)
    np.testing.assert_array_equal(auto.depth, stack.depth)
    np.testing.assert_array_equal(auto.cost, wide.cost)
    assert not np.array_equal(wide.cost, stack.cost)  # the units differ: the case below can fail
    heat = _job(scene, bvh, traversal="auto", mode="heatmap")
    assert heat.timings["traversal"] == "stack"
    np.testing.assert_array_equal(heat.color, _job(scene, bvh, traversal="stack", mode="heatmap").color)
    counted = _job(scene, bvh, traversal="auto", traversal_counters=True)
    assert counted.timings["traversal"] == "stack"
    np.testing.assert_array_equal(
        counted.counters, _job(scene, bvh, traversal="stack", traversal_counters=True).counters
    )


def test_auto_traversal_options():
    """ "auto" is a render option, made a walk by the backend (RenderOptions.for_backend); the
    library's default stays the report's stack walk; another traversal passes through unchanged."""
    options = bvhlab.RenderOptions(traversal="auto")
    assert bvhlab.RenderOptions().traversal == "stack"
    assert options.for_backend(cpu=True).traversal == "wide"
    assert options.for_backend(cpu=False).traversal == "stack"
    assert options.for_backend(cpu=True, counts_shown=True).traversal == "stack"
    assert options.replace(mode="heatmap").for_backend(cpu=True).traversal == "stack"
    for name in ("stack", "stackless", "wide"):
        assert options.replace(traversal=name).for_backend(cpu=False, counts_shown=True).traversal == name
    with pytest.raises(ValueError, match="auto, stack, stackless, wide"):
        bvhlab.RenderOptions(traversal="fastest")
    settings = bvhlab._core.RenderSettings()
    options.apply(settings)  # where nothing made it a walk: the core's default, which every backend has
    assert settings.traversal.name == bvhlab._core.DEFAULT_TRAVERSAL


def test_film_transparent_alpha_is_the_share_of_camera_rays_that_hit():
    """Film ▸ Transparent (Blender's): each pixel's alpha is the share of its 2×2 camera rays that
    hit something, counted here by Bvh.intersect over the tracer's own camera rays (pixel_ray);
    the colour is premultiplied: the opaque image less the sky's share; depth and cost unchanged;
    the overlay's lines count as covered; the heatmap stays opaque."""
    scene = showcase.whitted()
    bvh = bvhlab.build(scene)
    w, h, n = 40, 30, 2
    options = bvhlab.RenderOptions(samples_per_axis=n, film_transparent=True)
    film = _sized_job(scene, bvh, w, h, options)
    opaque = _sized_job(scene, bvh, w, h, options.replace(film_transparent=False))
    alpha = (camera_ray_hits(scene, bvh, w, h, options)["prim"] >= 0).mean(-1).astype(np.float32)
    np.testing.assert_array_equal(film.color[..., 3], alpha)
    assert 0.05 < (alpha == 0).mean() < 0.95 and ((alpha > 0) & (alpha < 1)).any()
    sky = np.array(scene.sky, np.float32)
    np.testing.assert_allclose(film.color[..., :3], opaque.color[..., :3] - sky * (1 - alpha)[..., None], atol=1e-6)
    np.testing.assert_array_equal(film.depth, opaque.depth)
    np.testing.assert_array_equal(film.cost, opaque.cost)
    assert np.all(opaque.color[..., 3] == 1)
    lines = _sized_job(scene, bvh, w, h, options.replace(overlay_depth=(0, 2))).color[..., 3]
    assert np.all(lines >= alpha) and (lines > alpha).sum() > 20  # the boxes' lines in the sky are opaque
    heat = _sized_job(scene, bvh, w, h, options.replace(mode="heatmap")).color
    assert np.all(heat[..., 3] == 1)


def _sized_job(scene, bvh, w, h, options):
    job = bvhlab.Renderer("cpu").start(scene, bvh, w, h, options=options)
    job.run()
    return job.result()


def test_heatmap_shows_more_box_tests_where_the_geometry_is():
    scene = showcase.whitted()
    heat = render(scene, 64, 48, mode="heatmap")
    assert np.all(heat[..., 3] == 1)
    sky_row, floor_row = heat[1, :, :3], heat[-2, :, :3]
    # the ramp runs blue (few) → red (many): the floor gets more red than the sky
    assert floor_row[:, 0].mean() + floor_row[:, 1].mean() > sky_row[:, 0].mean() + sky_row[:, 1].mean()


def test_supersampling_averages_samples():
    scene = showcase.five_spheres()
    one = render(scene, 48, 32, samples_per_axis=1)
    many = render(scene, 48, 32, samples_per_axis=4)
    assert np.abs(one - many).mean() < 0.03  # same picture...
    assert np.any(np.abs(one - many) > 0.05)  # ...with smoother silhouettes


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(width=0), "width"),
        (dict(height=-3), "height"),
        (dict(samples_per_axis=0), "samples_per_axis must be between 1 and 16"),
        (dict(samples_per_axis=17), "samples_per_axis must be between 1 and 16"),
        (dict(max_depth=99), r"max_depth must be between 0 and 15, got 99"),  # the option's name and its range
        (dict(max_depth=-1), r"max_depth must be between 0 and 15, got -1"),
        (dict(overlay_depth=(5, 2)), "greater"),
        (dict(mode="xray"), "unknown mode"),
        (dict(traversal="bfs"), "unknown traversal"),
        (dict(width=20000, height=10), "exceeds the device limit"),
        (dict(width=100000, height=100000), "exceeds"),
        (dict(heatmap_scale=0.0), "heatmap_scale"),
        (dict(heatmap_scale=float("inf")), "heatmap_scale"),
        (dict(heatmap_scale=-1.0), "heatmap_scale"),
        (dict(heatmap_scale=5e9), "heatmap_scale"),
        (dict(traversal="wide", traversal_counters=True), "'stack' or 'stackless'"),
    ],
)
def test_bad_settings(kwargs, match):
    scene = showcase.five_spheres()
    args = dict(width=32, height=32) | kwargs
    with pytest.raises(ValueError, match=match):
        bvhlab.render(scene, bvhlab.build(scene), backend="cpu", **args)


def test_nan_camera_is_rejected():
    with pytest.raises(ValueError, match="finite"):
        bvhlab.Camera((np.nan, 0, 0), (0, 0, 0))


def test_png_round_trip(tmp_path):
    from png_reader import read_png

    image = np.random.default_rng(0).random((5, 7, 4)).astype(np.float32)
    bvhlab.save_png(image, tmp_path / "x.png", premultiplied=False)  # straight: colour above alpha
    back = read_png(tmp_path / "x.png")
    assert back.shape == (5, 7, 4)
    srgb = np.where(image[..., :3] <= 0.0031308, 12.92 * image[..., :3], 1.055 * image[..., :3] ** (1 / 2.4) - 0.055)
    np.testing.assert_array_equal(back[..., :3], (srgb * 255 + 0.5).astype(np.uint8))


def test_auto_backend_prefers_a_gpu_and_says_which_device_and_why():
    """auto renders on a Vulkan GPU when there is one; when the only Vulkan device is a CPU driver
    (lavapipe) or there is none, on the CPU reference; the timings name the device and the reason."""
    scene = showcase.five_spheres()
    image, t = bvhlab.render(scene, bvhlab.build(scene), 16, 16, backend="auto")
    try:
        device = _core.VulkanRenderer("", False, False) if _core.HAS_VULKAN else None
    except bvhlab.VulkanUnavailable:
        device = None
    if device is None:
        assert t["backend"] == "cpu" and "Vulkan unavailable" in t["reason"]
    elif device.device_type == "cpu":
        assert t["backend"] == "cpu" and "CPU driver" in t["reason"] and device.device_name in t["reason"]
    else:
        assert t["backend"] == "vulkan" and t["device"] == device.device_name
    assert t["device"].startswith("CPU reference") == (t["backend"] == "cpu")
    assert ("fallback" in t) == (t["backend"] == "cpu")


def test_vulkan_settings_are_refused_on_the_cpu_backend():
    """validation and force_staging were ignored by the CPU backend, where `device` is refused."""
    for kwargs in (dict(validation=True), dict(force_staging=True)):
        with pytest.raises(ValueError, match="=True is a Vulkan setting, and the backend is 'cpu'"):
            bvhlab.Renderer("cpu", **kwargs)
    assert bvhlab.Renderer("cpu", validation=False).backend == "cpu"
