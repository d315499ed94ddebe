"""The tracers walk two-level trees (issue 34): an instanced scene renders as the same geometry
flattened into one mesh (rotation, non-uniform scale, mirroring, many instances of one mesh), and a
scene of one identity instance renders exactly as the flat scene, bit for bit."""

import math

import numpy as np
import pytest

import bvhlab
from bvhlab.library import procedural

MATERIALS = [
    bvhlab.Material(
        (0.8, 0.8, 0.8), reflective=0.2, transparent=0.3, ior=1.3
    ),  # meshes 1..: refraction sees the normals
    bvhlab.Material((0.9, 0.2, 0.1), reflective=0.0, transparent=0.0),
    bvhlab.Material((0.2, 0.3, 0.9), reflective=0.6, transparent=0.0),
]


def _transform(angle: float, axis, scale, move) -> np.ndarray:
    """Rotation about `axis` by `angle`, after scaling by `scale`, then moved by `move` (3×4)."""
    a = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    r = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)
    return np.concatenate([r @ np.diag(scale), np.reshape(move, (3, 1))], 1).astype(np.float32)


def _scene(transforms, mesh_of) -> bvhlab.Scene:
    """Mesh 0: small triangles and two spheres (materials 1 and 2); mesh 1: a torus knot (material 0)."""
    cloud = procedural.random_triangles(200, size=0.25, seed=3)
    spheres = np.array([[0.3, 0.4, 0.5, 0.2], [0.7, 0.6, 0.2, 0.15]], np.float32)
    knot = procedural.torus_knot(3000)
    camera = bvhlab.Camera((6.0, -9.0, 7.0), (2.0, 1.5, 0.5), (0.0, 0.0, 1.0), 50.0)
    light = bvhlab.Light((8.0, -4.0, 12.0), (1.0, 1.0, 1.0), 1.0)
    return bvhlab.Scene(
        triangles=cloud,
        spheres=spheres,
        meshes=[knot],
        materials=MATERIALS,
        tri_material=np.arange(len(cloud)) % 3,
        sphere_material=np.array([1, 2]),
        instance_mesh=np.asarray(mesh_of),
        instance_transforms=np.stack(transforms),
        camera=camera,
        light=light,
    )


def _flattened_outside_out(scene: bvhlab.Scene) -> bvhlab.Scene:
    """scene.flattened() with the winding of mirrored instances' triangles reversed: a mirrored mesh
    keeps its outside out (as the tracer's inverse-transpose normals, and Blender, keep it)."""
    flat = scene.flattened()
    tris = flat.triangles.copy()
    first = 0
    for k, t in zip(*scene.instances()):
        n = len(scene.mesh_triangles(int(k)))
        if np.linalg.det(t[:, :3].astype(np.float64)) < 0:
            tris[first : first + n] = tris[first : first + n][:, [0, 2, 1]]
        first += n
    flat.triangles = np.ascontiguousarray(tris)
    return flat


def _render(scene, tree, traversal="stack", **kw):
    job = bvhlab.Renderer("cpu").start(scene, tree, 96, 72, samples_per_axis=1, max_depth=4, traversal=traversal, **kw)
    job.run()
    return job.result(depth=True, cost=False)


def _assert_same_image(a, b, share=0.01):
    """Depth and colour agree but for a small share of pixels (grazing edges, where float rounding of
    the moved rays may pick a neighbour)."""
    depth_off = ~np.isclose(a.depth, b.depth, rtol=1e-4, atol=1e-5)
    color_off = np.abs(a.color - b.color).max(-1) > 2e-3
    assert depth_off.mean() <= share, f"{depth_off.sum()} pixels differ in depth"
    assert color_off.mean() <= share, f"{color_off.sum()} pixels differ in colour"


MANY = [
    _transform(0.0, (0, 0, 1), (1, 1, 1), (0, 0, 0)),
    _transform(0.7, (0, 0, 1), (1.5, 1.5, 1.5), (2.5, 0, 0)),  # mesh 0 again: rotated, uniform scale
    _transform(0.6, (1, 2, 3), (2.0, 0.5, 1.3), (3, 3, 0)),  # non-uniform scale
    _transform(1.1, (0, 1, 0), (-1, 1, 1), (0, 3, 0)),  # mirrored
    _transform(2.0, (1, 1, 0), (-0.7, -1.5, 1.5), (4, 1, 1)),  # mirrored, non-uniform
]


@pytest.mark.parametrize("traversal", ["stack", "stackless", "wide"])
def test_instanced_scene_renders_as_its_flattened_scene(traversal):
    scene = _scene(MANY, [0, 0, 1, 1, 1])
    flat = _flattened_outside_out(scene)
    two = bvhlab.build(scene)
    assert isinstance(two, bvhlab.InstancedBvh)
    a, b = _render(scene, two, traversal), _render(flat, bvhlab.build(flat), traversal)
    assert np.isfinite(a.depth).all() and (a.depth < 1e9).mean() > 0.2  # the scene fills the frame
    _assert_same_image(a, b)


def test_the_wide_traversal_walks_both_levels_to_the_stack_walks_image():
    """The CPU tracer's wide traversal answers each ray through the TLAS's and the meshes' 8-wide
    copies (tlas.h's queries), the hit mapped to the render scene's instance and primitive: the
    stack walk's image, bit for bit; also after the instances move (the new TLAS is the one walked)."""
    scene = _scene(MANY, [0, 0, 1, 1, 1])
    two = bvhlab.build(scene)
    stack, wide = _render(scene, two, "stack"), _render(scene, two, "wide")
    assert "wide walk" in wide.timings["device"]
    np.testing.assert_array_equal(stack.color, wide.color)
    np.testing.assert_array_equal(stack.depth, wide.depth)
    scene.instance_transforms = np.stack(
        [MANY[0], MANY[1], MANY[2], _transform(0.3, (1, 0, 0), (1, -1, 1), (0, 2, 1))] + MANY[4:]
    )
    two.place(*scene.instances())
    moved = _render(scene, two, "wide")
    assert np.abs(moved.color - wide.color).max() > 0.1
    np.testing.assert_array_equal(moved.color, _render(scene, two, "stack").color)


def test_instances_of_an_empty_mesh_render_with_every_traversal():
    """The TLAS leaves an instance of an empty mesh out of its tree; the wide traversal refused such
    a scene ("the wide traversal's TLAS and meshes are not the ones the scene was made from", helper
    probe 2026-12-07), which `bvhlab render` walks by default. Empty-mesh instances first, between
    and last: every traversal's image is the stack walk's, and the scene's without them."""
    scene = _scene(MANY, [0, 0, 1, 1, 1])
    with_empty = _scene(MANY, [0, 0, 1, 1, 1])
    with_empty.meshes = [scene.meshes[0], np.zeros((0, 3, 3), np.float32)]  # mesh 2: empty
    with_empty.instance_transforms = np.stack([MANY[1], *MANY[:3], MANY[2], *MANY[3:], MANY[4]])
    with_empty.instance_mesh = np.array([2, 0, 0, 1, 2, 1, 1, 2])
    two, without = bvhlab.build(with_empty), _render(scene, bvhlab.build(scene), "stack")
    stack = _render(with_empty, two, "stack")
    for traversal in ("stackless", "wide"):
        other = _render(with_empty, two, traversal)
        np.testing.assert_array_equal(other.color, stack.color, err_msg=traversal)
        np.testing.assert_array_equal(other.depth, stack.depth, err_msg=traversal)
    np.testing.assert_array_equal(stack.color, without.color)


def test_many_instances_of_one_mesh():
    rng = np.random.default_rng(7)
    transforms = [
        _transform(rng.uniform(0, 6), rng.normal(size=3), rng.uniform(0.2, 0.5, 3) * rng.choice([-1, 1], 3), (x, y, 0))
        for x in np.linspace(-1, 5, 8)
        for y in np.linspace(-1, 4, 8)
    ]
    scene = _scene(transforms, np.ones(len(transforms), int))
    flat = _flattened_outside_out(scene)
    a, b = _render(scene, bvhlab.build(scene)), _render(flat, bvhlab.build(flat))
    _assert_same_image(a, b)


def test_one_identity_instance_renders_as_the_flat_scene_bit_for_bit(small_scene):
    tris, spheres = small_scene
    flat = bvhlab.Scene(triangles=tris, spheres=spheres)
    mesh_of, transforms = flat.instances()
    spelled = bvhlab.Scene(triangles=tris, spheres=spheres, instance_mesh=mesh_of, instance_transforms=transforms)
    two = bvhlab.build(spelled)
    assert isinstance(two, bvhlab.InstancedBvh)
    for mode, traversal in (("shade", "stack"), ("heatmap", "stack"), ("shade", "wide"), ("heatmap", "wide")):
        a = _render(spelled, two, traversal, mode=mode)
        b = _render(flat, bvhlab.build(flat), traversal, mode=mode)
        np.testing.assert_array_equal(a.color, b.color)
        np.testing.assert_array_equal(a.depth, b.depth)


def test_an_instanced_scene_needs_its_two_level_tree():
    scene = _scene(MANY[:2], [0, 1])
    with pytest.raises(ValueError, match="two-level tree"):
        _render(scene, bvhlab.build(scene.flattened()))


def test_instances_move_between_renders():
    scene = _scene(MANY[:3], [0, 0, 1])
    tree = bvhlab.build(scene)
    renderer = bvhlab.Renderer("cpu")
    before, _ = renderer.render(scene, tree, 48, 36)
    moved = [MANY[0], MANY[1], _transform(0.6, (1, 2, 3), (2.0, 0.5, 1.3), (3, 1, 0))]
    scene.instance_transforms = np.stack(moved)
    tree.place(*scene.instances())
    after, _ = renderer.render(scene, tree, 48, 36)
    flat = _flattened_outside_out(scene)
    oracle, _ = renderer.render(flat, bvhlab.build(flat), 48, 36)
    assert np.abs(before - after).max() > 0.1
    assert (np.abs(after - oracle).max(-1) > 2e-3).mean() <= 0.01


def _two_cloud_scene() -> bvhlab.Scene:
    """Two instances (side by side, apart) of a mesh of two small triangle clouds, [0,1]³ and
    [3,4]×[0,1]², seen from the front and above: each BLAS splits the clouds apart at depth 1."""
    a = procedural.random_triangles(60, size=0.1, seed=11) * 0.8 + 0.1
    b = a + np.float32([3.0, 0.0, 0.0])
    mesh = np.ascontiguousarray(np.concatenate([a, b]), np.float32)
    transforms = np.stack([_transform(0.0, (0, 0, 1), (1, 1, 1), move) for move in ((0, 0, 0), (6, 0, 0))])
    return bvhlab.Scene(
        meshes=[mesh],
        instance_mesh=np.array([1, 1]),
        instance_transforms=transforms,
        camera=bvhlab.Camera((5.0, -9.0, 4.0), (5.0, 0.5, 0.5), (0.0, 0.0, 1.0), 55.0),
        light=bvhlab.Light((5.0, -6.0, 8.0), (1.0, 1.0, 1.0), 1.0),
        sky=(0.0, 0.0, 0.0),
    )


@pytest.mark.parametrize("backend", ["cpu", "vulkan"])
def test_the_overlay_pass_draws_the_level_asked_for(backend):
    """overlay_level "blas" traces the BLAS boxes moved into the world (here: depth 1, each cloud's
    box): a pixel on the vertical edge of a cloud's box where the two clouds split shows the line
    colour with "blas" and "both", and not with "tlas" (the TLAS's depth-1 boxes are the
    instances' boxes, with no edge there). The Vulkan tracer draws the same box list."""
    from test_render_cpu_overlay import near_pixels

    from bvhlab.overlay_levels import two_level_boxes

    if backend == "vulkan":
        try:
            bvhlab.Renderer("vulkan")
        except bvhlab.VulkanUnavailable as error:
            pytest.skip(f"no Vulkan: {error}")
    scene = _two_cloud_scene()
    tree = bvhlab.build(scene)
    line = (1.0, 0.0, 1.0)
    w, h = 160, 100

    def image(level):
        renderer = bvhlab.Renderer(backend)
        options = dict(overlay_depth=(1, 1), color_by_depth=False, line_color=line, line_width=2.0)
        job = renderer.start(scene, tree, w, h, samples_per_axis=1, overlay_level=level, **options)
        job.run()
        colour = job.result(depth=False, cost=False).color
        return np.all(np.abs(colour[..., :3] - np.float32(line)) < 1e-3, -1)

    boxes = two_level_boxes(tree, "blas", 1, 1)
    assert len(boxes.lo) == 4 and boxes.instances_shown == 2
    left = np.argmin(boxes.lo[:, 0])  # the first instance's first cloud
    # a point 70% up its front right edge (the TLAS box's front and back edges project elsewhere)
    edge = (boxes.hi[left, 0], boxes.lo[left, 1], boxes.lo[left, 2] + 0.7 * (boxes.hi[left, 2] - boxes.lo[left, 2]))
    pixels = near_pixels(scene.camera, w, h, edge)
    blas, both, tlas = image("blas"), image("both"), image("tlas")
    assert any(blas[p] and both[p] and not tlas[p] for p in pixels), [(blas[p], both[p], tlas[p]) for p in pixels]
    assert blas.sum() > 100 and tlas.sum() > 100 and (both & ~blas & ~tlas).sum() < 0.05 * both.sum()


def test_blas_boxes_in_the_overlay_pass_are_capped():
    """3,000 instances of a 2,000-triangle mesh have some 3M BLAS boxes: the render scene's overlay
    holds the TLAS's boxes and the BLAS boxes of the first instances that fit the cap, as the
    add-on's viewport overlay draws them (overlay_levels.two_level_boxes)."""
    from bvhlab._render_scene import SceneCache
    from bvhlab.overlay_levels import MAX_OVERLAY_BOXES, two_level_boxes

    knot = procedural.torus_knot(1000)
    n = 3000
    transforms = np.tile(np.eye(4, dtype=np.float32)[:3], (n, 1, 1))
    transforms[:, :, 3] = np.stack([np.arange(n) % 60 * 3.0, np.arange(n) // 60 * 3.0, np.zeros(n)], 1)
    scene = bvhlab.Scene(
        meshes=[knot],
        instance_mesh=np.ones(n, np.int64),
        instance_transforms=transforms,
        camera=bvhlab.Camera((90.0, -60.0, 80.0), (90.0, 75.0, 0.0)),
    )
    tree = bvhlab.build(scene)
    options = bvhlab.RenderOptions(overlay_depth=(0, 40), overlay_level="both")
    render_scene = SceneCache().get(scene, tree, options)
    want = two_level_boxes(tree, "both", 0, 40)
    assert 0 < want.instances_shown < n and render_scene.overlay_box_count == len(want.lo) <= MAX_OVERLAY_BOXES
    assert SceneCache().get(scene, tree, options.replace(overlay_level="tlas")).overlay_box_count == 2 * n - 1


def test_overlay_boxes_out_of_order_or_not_boxes_are_refused():
    """RenderScene.with_overlay_boxes (what the cache calls for overlay_level) refuses boxes not
    sorted by depth, a NaN corner, lo > hi and mismatched lengths with a ValueError."""
    from bvhlab._render_scene import SceneCache

    scene = _two_cloud_scene()
    render_scene = SceneCache().get(scene, bvhlab.build(scene))
    lo = np.zeros((2, 3), np.float32)
    hi = np.ones((2, 3), np.float32)
    ok = render_scene.with_overlay_boxes(lo, hi, np.array([0, 3], np.uint8))
    assert ok.overlay_box_count == 2 and render_scene.overlay_box_count == 3  # the TLAS's, untouched
    assert ok.height == render_scene.height  # the tree's, not the boxes' (the heatmap scale reads it)
    bad = [
        (lo, hi, np.array([3, 0], np.uint8), "sorted by depth"),
        (np.float32([[0, 0, np.nan], [0, 0, 0]]), hi, np.zeros(2, np.uint8), "not a box"),
        (hi + 1, hi, np.zeros(2, np.uint8), "not a box"),
        (lo, hi[:1], np.zeros(2, np.uint8), "one lo, one hi"),
    ]
    for a, b, depth, message in bad:
        with pytest.raises(ValueError, match=message):
            render_scene.with_overlay_boxes(a, b, depth)


def test_a_shared_meshs_new_material_indices_are_rendered():
    """One Renderer, a two-level scene rendered, then the shared mesh's faces given another material
    (the tree kept: nothing moved): the render cache's key left the meshes' material indices out,
    and the old colours were traced (a probe: 736 pixels of F12 and the viewport stayed red)."""
    quad = np.array([[[-1, -1, 0], [1, -1, 0], [1, 1, 0]], [[-1, -1, 0], [1, 1, 0], [-1, 1, 0]]], np.float32)
    transforms = np.tile(np.eye(3, 4, dtype=np.float32), (2, 1, 1))
    transforms[0, :, 3], transforms[1, :, 3] = (-1.2, 0, 0), (1.2, 0, 0)
    materials = [bvhlab.Material(color=(1, 0, 0)), bvhlab.Material(color=(0, 0, 1))]
    camera = bvhlab.Camera((0, 0, 6), (0, 0, 0), (0, 1, 0), 45.0)

    def scene(index):
        return bvhlab.Scene(
            triangles=np.zeros((0, 3, 3), np.float32), materials=materials, meshes=[quad],
            mesh_tri_material=[np.array([index, index], np.int32)], instance_mesh=np.ones(2, np.int32),
            instance_transforms=transforms, camera=camera,
        )  # fmt: skip

    bvh = bvhlab.build(scene(0))
    renderer = bvhlab.Renderer("cpu")

    def colour(renderer, s):
        job = renderer.start(s, bvh, 32, 24)
        job.run()
        return job.result().color

    red = colour(renderer, scene(0))
    again = colour(renderer, scene(1))
    fresh = colour(bvhlab.Renderer("cpu"), scene(1))
    np.testing.assert_array_equal(again, fresh)
    assert red[12, 8, 0] > 0.5 and again[12, 8, 2] > 0.5 and again[12, 8, 0] < 0.1


def _uv_sphere(nu=96, nv=48):
    th, ph = np.linspace(0, np.pi, nv + 1), np.linspace(0, 2 * np.pi, nu + 1)
    p = np.stack([np.sin(th)[:, None] * np.cos(ph), np.sin(th)[:, None] * np.sin(ph), np.cos(th)[:, None] + 0 * ph], -1)
    tris = [[p[i, j], p[i + 1, j], p[i, j + 1]] for i in range(1, nv) for j in range(nu)]
    tris += [[p[i + 1, j], p[i + 1, j + 1], p[i, j + 1]] for i in range(nv - 1) for j in range(nu)]
    return np.array(tris, np.float32)


def test_a_skewed_stretched_instance_does_not_shadow_itself():
    """A sphere instanced by rotation · diag(10, 1, 0.1) · rotation about 100 from the origin: its rays
    leave from its triangles' points in the world, through the inverted transform, whose rounding
    grows with how stretched and skewed it is (a bound of 16 roundings of |p| let 11 of 2,294 pixels
    shadow themselves, a review found). Against its flattened copy, pixel for pixel."""
    rng = np.random.default_rng(2)

    def rotation():
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        return q if np.linalg.det(q) > 0 else q * [-1, 1, 1]

    a = rotation() @ np.diag([10, 1, 0.1]) @ rotation()
    t = np.array([100.0, 50.0, 30.0])
    mesh = _uv_sphere()
    world = (np.einsum("ij,ntj->nti", a, mesh.astype(np.float64)) + t).astype(np.float32)
    lo, hi = world.reshape(-1, 3).min(0), world.reshape(-1, 3).max(0)
    centre, size = (lo + hi) / 2, float(np.linalg.norm(hi - lo))
    camera = bvhlab.Camera(tuple(centre + np.array([0.3, -1.0, 0.6]) * size * 1.2), tuple(centre), (0, 0, 1), 40.0)
    light = bvhlab.Light(tuple(centre + np.array([1.0, -0.5, 1.2]) * size))
    instanced = bvhlab.Scene(
        triangles=np.zeros((0, 3, 3), np.float32), meshes=[mesh], instance_mesh=np.ones(1, np.int32),
        instance_transforms=np.hstack([a, t[:, None]]).astype(np.float32)[None], camera=camera, light=light,
    )  # fmt: skip

    def colour(scene):
        job = bvhlab.Renderer("cpu").start(scene, bvhlab.build(scene), 320, 240)
        job.run()
        return job.result().color[..., :3]

    got, flat = colour(instanced), colour(instanced.flattened())
    assert (flat.max(-1) > 0.3).sum() > 1000, "the test's view: the sphere lit"
    assert int((np.abs(got - flat).max(-1) > 0.1).sum()) == 0


def test_a_tree_placed_otherwise_than_its_scene_is_refused_and_renders_once_placed_again():
    """A two-level tree renders the scene it was placed for: a scene whose instance moved since,
    or one with an instance more or less, is refused (it rendered the tree's placement without a
    word, helper probe), as a flat tree over other geometry is; placed again, the tree renders
    the moved scene exactly as a tree built over it."""
    placed = [_transform(0.0, (0, 0, 1), (1, 1, 1), (0, 0, 0)), _transform(0.5, (0, 1, 0), (1, 1, 1), (3, 0, 0))]
    tree = bvhlab.build(_scene(placed, [0, 1]))
    moved = _scene([placed[0], _transform(0.5, (0, 1, 0), (1, 1, 1), (0, 3, 0))], [0, 1])
    with pytest.raises(ValueError, match="not placed as the scene's"):
        bvhlab.render(moved, tree, 48, 32, backend="cpu")
    with pytest.raises(ValueError, match="not placed as the scene's"):
        bvhlab.render(_scene(placed, [0, 0]), tree, 48, 32, backend="cpu")  # another mesh in a place
    with pytest.raises(ValueError, match="the tree has 2 instances, the scene 3"):
        bvhlab.render(_scene([*placed, placed[1]], [0, 1, 1]), tree, 48, 32, backend="cpu")
    flat = bvhlab.Scene(triangles=moved.triangles, camera=moved.camera, light=moved.light)
    with pytest.raises(ValueError, match="the tree has 2 meshes, the scene 1"):
        bvhlab.render(flat, tree, 48, 32, backend="cpu")
    # the tree keeps copies: a scene's transforms changed in place after the build are not its own
    built = _scene(placed, [0, 1])
    own = bvhlab.build(built)
    built.instance_transforms[1, :, 3] = (0.0, 3.0, 0.0)
    with pytest.raises(ValueError, match="not placed as the scene's"):
        bvhlab.render(built, own, 48, 32, backend="cpu")
    tree.place(*moved.instances())
    image, _ = bvhlab.render(moved, tree, 48, 32, backend="cpu")
    expected, _ = bvhlab.render(moved, bvhlab.build(moved), 48, 32, backend="cpu")
    assert np.array_equal(image, expected)
