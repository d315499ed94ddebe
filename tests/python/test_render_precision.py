"""The tracer's ray tests (shaders/tracer/geometry.glsl, the CPU reference and Vulkan run the same
code) on the cases that float32 rounding decides: rays through the shared edges and vertices of a
closed mesh never leak (watertight test, Woop, Benthin and Wald 2013), and rays beside a small
distant sphere miss it (Haines et al., Ray Tracing Gems 2019 ch. 7). Checked against geometry
worked out here in float64, on both backends and both traversals (and the CPU tracer's wide one,
which answers each ray through the tree's 8-wide copy with the same ray tests)."""

import functools
import math

import numpy as np
import pytest
from oracles import Whitted64

import bvhlab
from bvhlab.library import procedural

SKY_DEPTH = 1e10  # RenderResult.depth where nothing was hit


@pytest.fixture(scope="module", params=["cpu", "vulkan"])
def renderer(request):
    r = bvhlab.Renderer(request.param, validation=True) if request.param == "vulkan" else bvhlab.Renderer("cpu")
    yield r
    assert r.validation_errors == 0, r.validation_messages()


def depth_pass(renderer, scene, size, traversal, camera):
    if traversal == "wide" and renderer.backend == "vulkan":
        pytest.skip("the wide traversal is the CPU tracer's (Vulkan refuses it: test_render_vulkan)")
    job = renderer.start(
        scene, bvhlab.build(scene, method="median"), size, size, camera=camera, traversal=traversal, max_depth=0
    )
    job.run()
    return job.result(color=False, cost=False).depth


def cube_points(h):
    """The corners of the cube [-h, h]³ and the midpoints of its edges (grid vertices of box_room
    with an even number of divisions)."""
    corners = [(x, y, z) for x in (-h, h) for y in (-h, h) for z in (-h, h)]
    edges = [tuple(np.roll((a, b, 0.0), k)) for k in range(3) for a in (-h, h) for b in (-h, h)]
    return corners + edges


@pytest.mark.parametrize("traversal", ["stack", "stackless", "wide"])
def test_rays_through_shared_edges_and_vertices_of_a_closed_mesh_never_miss(renderer, traversal):
    """From the centre of a closed cube (six 8×8 grids of two triangles a cell), looking straight at
    each corner and each edge's midpoint: the centre pixel's ray (an odd image) runs exactly
    through that vertex, where three to six triangles meet, and the rays around it cross the
    cube's edges and the grid's diagonals. Every pixel must hit, at the depth of the cube's wall."""
    h, size = 1.0, 33
    scene = bvhlab.Scene(triangles=procedural.box_room(2 * h, 8))
    for point in cube_points(h):
        up = (0.0, 0.0, 1.0) if point[2] == 0.0 or abs(point[0]) + abs(point[1]) > 0 else (0.0, 1.0, 0.0)
        camera = bvhlab.Camera(position=(0.0, 0.0, 0.0), look_at=point, up=up, fov_y=60.0)
        depth = depth_pass(renderer, scene, size, traversal, camera)
        sky = np.count_nonzero(depth >= SKY_DEPTH)
        assert sky == 0, f"{renderer.backend} {traversal}: {sky} rays leaked out of the cube towards {point}"
        centre = depth[size // 2, size // 2]
        assert centre == pytest.approx(math.hypot(*point), rel=1e-5), (point, centre)


@pytest.mark.parametrize("traversal", ["stack", "stackless", "wide"])
def test_rays_beside_a_small_distant_sphere_miss_it_in_the_tracer(renderer, traversal):
    """A sphere of radius 1 mm 100 m away filling a 61-pixel image about 60 radii across: the
    pixels whose ray passes within the radius (worked out in float64) hit it at its distance, all
    others are sky. The old discriminant b² - a·c hit rays up to about 24 radii beside it."""
    r, distance, size, radii_across = 1e-3, 100.0, 61, 60.0
    scene = bvhlab.Scene(spheres=np.array([[distance, 0.0, 0.0, r]], np.float32))
    tan_half = radii_across / 2 * r / distance
    camera = bvhlab.Camera(
        position=(0.0, 0.0, 0.0),
        look_at=(1.0, 0.0, 0.0),
        up=(0.0, 0.0, 1.0),
        fov_y=math.degrees(2 * math.atan(tan_half)),
    )
    depth = depth_pass(renderer, scene, size, traversal, camera)
    # each pixel's ray (1, x, y) in float64: its distance from the centre
    s = ((np.arange(size) + 0.5) / size * 2 - 1) * tan_half
    x, y = np.meshgrid(s, s)
    beside = distance * np.hypot(x, y) / np.sqrt(1 + x * x + y * y)
    inside, outside = beside < r * 0.99, beside > r * 1.01
    assert inside.sum() >= 3 and outside.sum() > 3000
    hit = depth < SKY_DEPTH
    assert hit[inside].all(), f"{renderer.backend} {traversal}: rays through the sphere missed it"
    assert not hit[outside].any(), (
        f"{renderer.backend} {traversal}: {np.count_nonzero(hit & outside)} rays "
        f"up to {beside[hit & outside].max() / r:.1f} radii beside the sphere hit it"
    )
    np.testing.assert_allclose(depth[inside], distance - r, rtol=2e-5)


# -- where secondary and shadow rays start (shaders/tracer/ray_offset.glsl) -------------------------
# Until 2026-12 they started 1e-4 of the scene's diagonal off the surface: below float32's spacing
# far from the origin (shadow acne), far above a small object's size in a large scene.

SIZE = (40, 30)


def spheres_on_a_floor(offset):
    """An 8-unit floor, two spheres and the light, moved by `offset` on every axis (exactly
    representable at 1e5: the same scene in float32 as at the origin)."""
    floor = np.array([[[-4, -4, -1], [4, -4, -1], [4, 4, -1]], [[-4, -4, -1], [4, 4, -1], [-4, 4, -1]]], np.float64)
    spheres = np.array([[0, 0, 0, 0.9], [1.5, 1, 0, 0.5]])
    spheres[:, :3] += offset

    def at(p):
        return tuple(np.array(p, float) + offset)

    return bvhlab.Scene(
        triangles=(floor + offset).astype(np.float32),
        spheres=spheres.astype(np.float32),
        materials=[
            bvhlab.Material((0.8, 0.8, 0.8)),
            bvhlab.Material((0.9, 0.5, 0.2)),
            bvhlab.Material((0.2, 0.2, 0.9)),
        ],
        sphere_material=[1, 2],
        camera=bvhlab.Camera(at((0, -6, 1.5)), at((0, 0, 0))),
        light=bvhlab.Light(at((2, -3, 5))),
    )


def glass_and_mirror_on_a_floor(half):
    """A 1-unit glass sphere, a mirror sphere and a red one on a floor `half` units across each
    way (Blender's usual large ground plane under small objects)."""
    floor = np.array([[[-1, -1, -1], [1, -1, -1], [1, 1, -1]], [[-1, -1, -1], [1, 1, -1], [-1, 1, -1]]], np.float32)
    return bvhlab.Scene(
        triangles=floor * np.float32([half, half, 1]),
        spheres=np.array([[0, 0, 0, 1], [2.2, 0.5, -0.4, 0.6], [-2, 1.5, -0.5, 0.5]], np.float32),
        materials=[
            bvhlab.Material((0.8, 0.8, 0.8)),
            bvhlab.Material((1, 1, 1), transparent=0.9, ior=1.5),
            bvhlab.Material((0.9, 0.9, 0.9), reflective=0.9),
            bvhlab.Material((0.9, 0.2, 0.1)),
        ],
        sphere_material=[1, 2, 3],
        camera=bvhlab.Camera((0, -6, 1.5), (0, 0, -0.3)),
        light=bvhlab.Light((2, -3, 5)),
    )


def pixels_off(image, reference):
    return int((np.abs(image[..., :3] - reference).max(-1) > 0.05).sum())


@pytest.fixture(scope="module")
def far_reference():
    return Whitted64(spheres_on_a_floor(0.0), max_depth=5).render(spheres_on_a_floor(0.0).camera, *SIZE)


@pytest.mark.parametrize("offset", [0.0, 3e4, 1e5])
def test_no_shadow_acne_far_from_the_origin(renderer, far_reference, offset):
    """The scene moved 1e5 on every axis is the same float32 scene, but its hit points are only
    known to float32's spacing there (0.0078): each ray starts off its surface by its own point's
    error bound. With the scene-wide offset: 25 of 1,200 pixels off at 3e4, 48 at 1e5 (acne on the
    floor and the spheres); now 0, and 1 at 1e5 (a shadow's edge, moved by the spacing)."""
    scene = spheres_on_a_floor(offset)
    image = renderer.render(scene, bvhlab.build(scene), *SIZE)[0]
    assert pixels_off(image, far_reference) <= (2 if offset >= 1e5 else 0)


@functools.cache
def floor_reference(half):
    scene = glass_and_mirror_on_a_floor(half)
    return Whitted64(scene, max_depth=6).render(scene.camera, *SIZE)


@pytest.mark.parametrize("half", [5, 500, 50000])
def test_a_large_floor_keeps_small_objects_intact(renderer, half):
    """The floor's size does not change the spheres near the camera (against the float64 tracer
    on the same scene): with 1e-4 of the diagonal as the offset, 35 of 1,200 pixels were off at
    half-size 500 and 153 at 50,000 (the refracted ray started past the glass sphere's back, the
    mirror sphere's shadow was gone); now none, or one at 50,000 (a shadow's edge, which float32
    and float64 round to different sides)."""
    scene = glass_and_mirror_on_a_floor(half)
    image = renderer.render(scene, bvhlab.build(scene), *SIZE, max_depth=6)[0]
    assert pixels_off(image, floor_reference(half)) <= (1 if half > 500 else 0)
