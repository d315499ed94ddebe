"""The tracer's BVH overlay on the CPU reference (report §3.3), checked against geometry computed
here: lines occlude and are occluded by surfaces, a line's width, box edges lying on a surface."""

import dataclasses

import numpy as np
import pytest
from test_render_cpu import SKY, project

import bvhlab
from bvhlab.library import showcase


def overlay_scene():
    """A small sphere in front of a large one, seen from close by: the small sphere's box has its
    front edges in front of the big sphere (visible) and its back edges behind itself (hidden)."""
    spheres = np.array([[0, 0, 0, 0.5], [0, 6, 0, 3]], np.float32)
    return bvhlab.Scene(
        spheres=spheres,
        materials=[bvhlab.Material((0.9, 0.3, 0.3)), bvhlab.Material((0.3, 0.3, 0.9))],
        sphere_material=[0, 1],
        camera=bvhlab.Camera((0, -3, 0), (0, 0, 0), fov_y=30),
        light=bvhlab.Light((0, -10, 5)),
        sky=SKY,
    )


def near_pixels(camera, w, h, point):
    x, y = project(camera, w, h, point)
    return [(int(y) + dy, int(x) + dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1)]


def test_overlay_lines_occlude_and_are_occluded():
    scene = overlay_scene()
    bvh = bvhlab.build(scene)
    w, h = 160, 120
    plain, _ = bvhlab.render(scene, bvh, w, h, backend="cpu")
    line_color = np.float32([0.2, 0.9, 0.4])  # not the default: the setting reaches the overlay
    lines, _ = bvhlab.render(
        scene, bvh, w, h, backend="cpu", overlay_depth=(1, 1), color_by_depth=False, line_color=tuple(line_color)
    )
    is_line = np.all(np.abs(lines[..., :3] - line_color) < 1e-6, -1)
    # every pixel is either unchanged or shows the line colour; some lines are drawn
    assert np.all(is_line | np.all(lines == plain, -1))
    assert is_line.sum() > 50
    # the small sphere's box is [-0.5, 0.5]³; midpoints of its right vertical edges:
    front = (0.5, -0.5, 0.0)  # the ray there misses the small sphere and meets the big one farther
    back = (0.5, 0.5, 0.0)  # the ray there passes through the small sphere first
    assert any(is_line[p] for p in near_pixels(scene.camera, w, h, front))
    assert not any(is_line[p] for p in near_pixels(scene.camera, w, h, back))


@pytest.mark.parametrize("width", [2, 3, 4.6])
def test_overlay_line_width_widens_every_line_in_its_minor_direction(width):
    """`line_width` w on the CPU: each column (row) of a 1-pixel line becomes the round(w) pixels
    of the minor axis centred on it, as Vulkan's wide Bresenham lines (lavapipe: the same pixels,
    tests/python/test_render_vulkan.py); the CPU drew 1-pixel lines whatever the width."""
    # two specks far apart: the root box's twelve edges over the sky, none hidden
    scene = bvhlab.Scene(
        spheres=np.array([[-1, -1, -0.6, 0.02], [1, 1, 0.6, 0.02]], np.float32),
        camera=bvhlab.Camera((2, -6, 1.5), (0, 0, 0), fov_y=40),
        sky=SKY,
    )
    bvh = bvhlab.build(scene)
    w, h = 161, 121
    color = np.float32([0.2, 0.9, 0.4])
    kw = dict(backend="cpu", overlay_depth=(0, 0), color_by_depth=False, line_color=tuple(color))
    thin, _ = bvhlab.render(scene, bvh, w, h, **kw)
    wide, _ = bvhlab.render(scene, bvh, w, h, line_width=width, **kw)
    is_thin = np.all(np.abs(thin[..., :3] - color) < 1e-6, -1)
    is_wide = np.all(np.abs(wide[..., :3] - color) < 1e-6, -1)
    assert is_thin.sum() > 100
    n = round(width)
    # the wide lines hold the thin ones' pixels, and about n times as many (fewer where lines
    # cross or meet at corners)
    assert np.all(is_wide[is_thin])
    assert 0.8 * n * is_thin.sum() <= is_wide.sum() <= n * is_thin.sum()
    # no pixel of a wide line is farther than n/2 pixels from a thin line's
    ys, xs = np.nonzero(is_wide)
    ty, tx = np.nonzero(is_thin)
    near = np.min(np.maximum(np.abs(ys[:, None] - ty[None]), np.abs(xs[:, None] - tx[None])), axis=1)
    assert near.max() <= n // 2


@pytest.mark.parametrize("place", [(6.0, 4.0), (6.0, 0.6), (20.0, 3.0)], ids=["above", "grazing", "far"])
@pytest.mark.parametrize("width", [1, 3, 8, 16])
def test_a_box_edge_lying_on_a_surface_is_drawn_and_one_under_it_is_not(place, width):
    """The overlay's lines over a floor whose own box lies on it (a flat root box), against the
    same box's edges over the sky (two specks at the floor's corners give the same box): the floor
    hides no line pixel the sky shows but a few where it is seen almost edge-on. Compared exactly,
    rounding hid some (201 of 292 pixels shown); stopping the query 2^-12 short of the line
    (LINE_ON_SURFACE) 218: the far edge's pixels whose centres meet the floor in front of the line
    (up to half the line's width off it) were hidden until the slope bias (line_on_surface,
    shade.glsl), at widths 1 and 3; from width 8 on, pixels of a wide line lie farther off its
    centre than the slope bias of a pixel reaches: line_on_surface tests the line's own point (the
    overlay pass's, per pixel) against the floor's plane. Boxes 0.3 under a floor stay hidden: the
    bias is a pixel's worth of depth (as polygon offset's, lines less deep under a surface than
    that may show); test_box_edges_under_a_floor_stay_hidden_at_every_width."""
    distance, height = place
    floor = showcase.quad((-2, -2, 0), (2, -2, 0), (2, 2, 0), (-2, 2, 0))
    specks = np.array(
        [[(-2, -2, 0), (-1.99, -2, 0), (-2, -1.99, 0)], [(2, 2, 0), (2, 1.99, 0), (1.99, 2, 0)]], np.float32
    )
    camera = bvhlab.Camera((0.3, -distance, height), (0.0, 0.0, 0.0), fov_y=50.0)
    options = dict(
        overlay_depth=(0, 0), color_by_depth=False, line_color=(1.0, 0.0, 1.0), traversal="stack", line_width=width
    )

    def line_pixels(triangles):
        scene = bvhlab.Scene(triangles=triangles, camera=camera)
        image, _ = bvhlab.render(scene, bvhlab.build(scene), 200, 150, backend="cpu", **options)
        return np.all(image[..., :3] == (1.0, 0.0, 1.0), -1)

    on_floor, over_sky = line_pixels(floor), line_pixels(specks)
    assert over_sky.sum() > 60 * min(width, 3), "the box's edges are drawn"
    assert not (on_floor & ~over_sky).any()
    assert on_floor.sum() >= 0.97 * over_sky.sum(), (on_floor.sum(), over_sky.sum())
    # the specks' boxes 0.3 under a floor beyond the clipping distance everywhere but under them
    # (its own boxes' edges, on it, clipped away): nothing of them shows
    wide_floor = showcase.quad((-1e3, -1e3, 0), (1e3, -1e3, 0), (1e3, 1e3, 0), (-1e3, 1e3, 0))
    scene = bvhlab.Scene(
        triangles=np.concatenate([wide_floor, specks - np.float32([0, 0, 0.3])]),
        camera=dataclasses.replace(camera, clip_end=50.0),
    )
    bvh = bvhlab.build(scene, method="median", max_leaf_size=1)
    all_depths = (0, bvh.stats["height"] - 1)
    image, _ = bvhlab.render(scene, bvh, 200, 150, backend="cpu", **{**options, "overlay_depth": all_depths})
    under = np.all(image[..., :3] == (1.0, 0.0, 1.0), -1)
    assert not under.any(), under.sum()


def lines_over_a_floor(render, under, width):
    """The line pixels of a 2×2×0.5 box `under` units under a wide opaque floor (None: no box), in
    the window around it, seen from 20 units 8.5° above the floor at 160×120 (a helper's audit).
    `render(scene, bvh, width, height, **options)` is a backend's."""
    floor = showcase.quad((-50, -50, 0), (50, -50, 0), (50, 50, 0), (-50, 50, 0))
    triangles = (
        floor if under is None else np.concatenate([floor, showcase.box_mesh((-1, -1, -under - 0.5), (1, 1, -under))])
    )
    camera = bvhlab.Camera((0.0, -20.0, 3.0), (0.0, 0.0, 0.0), fov_y=45.0)
    scene = bvhlab.Scene(triangles=triangles.astype(np.float32), camera=camera, light=bvhlab.Light((5.0, -10.0, 10.0)))
    bvh = bvhlab.build(scene, max_leaf_size=1)
    options = dict(overlay_depth=(0, 10), line_width=width, color_by_depth=False, line_color=(1.0, 0.0, 1.0))
    image, _ = render(scene, bvh, 160, 120, **options)
    return int(np.all(image[56:76, 66:94, :3] == (1.0, 0.0, 1.0), -1).sum())


@pytest.mark.parametrize("width", [1, 3, 8, 16])
def test_box_edges_under_a_floor_stay_hidden_at_every_width(width):
    """A box 0.3 (1.0) under a floor seen from 20 units 8.5° above it: none of its edges shows at
    any line width. A slope bias that grew with the width (half the width's depth across the floor)
    let 29, 150 and 271 of its line pixels through at widths 3, 8 and 16 (0.3 under), 28 and 131 at
    8 and 16 (1.0 under); line_on_surface tests the line's own point against the floor's plane."""

    def render(*args, **options):
        return bvhlab.render(*args, backend="cpu", **options)

    assert lines_over_a_floor(render, None, width) == 0
    assert lines_over_a_floor(render, 0.3, width) == 0
    assert lines_over_a_floor(render, 1.0, width) == 0
