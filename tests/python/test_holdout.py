"""Holdout materials (Cycles' Holdout: Object ▸ Visibility ▸ Holdout, a view layer's holdout
collection, the Holdout shader): a camera ray that meets one adds no colour and no alpha, and
the pixel's depth there is the sky's, on an opaque film too; other rays see it black; its
shadow stays. Each pixel's alpha is checked against Bvh.intersect over the tracer's own camera
rays (pixel_ray), the CPU reference against Vulkan (lavapipe, validation on), and a trace cut
into many dispatches against one run."""

import dataclasses

import numpy as np
import pytest
from oracles import camera_ray_hits

import bvhlab
from bvhlab.library import showcase

W, H, N = 48, 36, 2
HOLDOUT_SPHERE = 2  # whitted's blue sphere (material 4); the mirror (sphere 0) reflects it


def holdout_scene(film_transparent=False):
    scene = showcase.whitted()
    materials = list(scene.materials)
    materials.append(dataclasses.replace(materials[4], holdout=True))
    sphere_material = scene.sphere_material.copy()
    sphere_material[HOLDOUT_SPHERE] = len(materials) - 1
    return dataclasses.replace(scene, materials=materials, sphere_material=sphere_material)


def camera_hits(scene, bvh, options):
    """Of each of the tracer's camera rays (H, W, N·N), by Bvh.intersect: whether it hits
    something, and whether what it hits is the holdout sphere."""
    hit = camera_ray_hits(scene, bvh, W, H, options)
    return hit["prim"] >= 0, (hit["kind"] == 1) & (hit["prim"] == HOLDOUT_SPHERE)


def cpu_result(scene, bvh, options):
    job = bvhlab.Renderer("cpu").start(scene, bvh, W, H, options=options)
    job.run()
    return job.result()


@pytest.mark.parametrize("film_transparent", [False, True], ids=["opaque_film", "transparent_film"])
def test_a_holdouts_pixels_are_holes_of_the_share_of_rays_that_meet_it(film_transparent):
    scene = holdout_scene()
    bvh = bvhlab.build(scene)
    options = bvhlab.RenderOptions(samples_per_axis=N, film_transparent=film_transparent)
    result = cpu_result(scene, bvh, options)
    hits, held = camera_hits(scene, bvh, options)
    shows = ~held if not film_transparent else hits & ~held
    alpha = shows.mean(-1).astype(np.float32)
    assert held.all(-1).sum() > 20 and (held.any(-1) & ~held.all(-1)).sum() > 5  # whole and edge pixels
    np.testing.assert_array_equal(result.color[..., 3], alpha)
    whole = held.all(-1)
    assert np.all(result.color[whole] == 0)  # no colour, no alpha
    assert np.all(result.depth[whole] == 1e10)  # the sky's depth, as Cycles writes it there
    # without bounces, what the holdout is not seen by is the scene without it as a holdout (its
    # shadow stays): the same colour where no camera ray meets it
    plain = cpu_result(showcase.whitted(), bvh, options.replace(max_depth=0))
    flat = cpu_result(scene, bvh, options.replace(max_depth=0))
    clear = ~held.any(-1)
    np.testing.assert_array_equal(flat.color[clear][:, :3], plain.color[clear][:, :3])
    np.testing.assert_array_equal(flat.depth[clear], plain.depth[clear])


def test_other_rays_see_a_holdout_black():
    """With a floor that reflects half the light, the floor's pixels that reflect the holdout
    sphere darken to the floor's own shading (the render without bounces), where a render whose
    sphere is plain blue shows its blue."""

    def mirror_floor(scene):
        materials = [dataclasses.replace(m, reflective=0.5) for m in scene.materials[:2]] + scene.materials[2:]
        return dataclasses.replace(scene, materials=materials)

    scene, plain_scene = mirror_floor(holdout_scene()), mirror_floor(showcase.whitted())
    bvh = bvhlab.build(scene)
    options = bvhlab.RenderOptions(samples_per_axis=1, max_depth=1)
    held = cpu_result(scene, bvh, options).color
    plain = cpu_result(plain_scene, bvh, options).color
    floor_only = cpu_result(scene, bvh, options.replace(max_depth=0)).color
    # the opaque pixels that changed: the floor (and the mirror sphere) where they reflect it
    reflecting = (np.abs(held - plain).max(-1) > 1e-6) & (held[..., 3] == 1)
    assert reflecting.sum() > 20
    # a holdout adds nothing to the reflecting surface's own shading there
    np.testing.assert_allclose(held[reflecting], floor_only[reflecting], atol=1e-6)
    assert np.all(plain[reflecting][:, 2] > held[reflecting][:, 2])  # the blue it reflected is gone


def test_a_holdout_trace_cut_into_many_dispatches_is_the_same():
    """A render cut into dispatches of 20 steps equals one run: a camera ray meeting a holdout ends
    its sample in the step that meets it (so nothing of it is saved between dispatches: state.glsl)."""
    scene = holdout_scene()
    bvh = bvhlab.build(scene)
    options = bvhlab.RenderOptions(samples_per_axis=N, max_depth=2)
    one = cpu_result(scene, bvh, options)
    cut = cpu_result(scene, bvh, options.replace(steps_per_dispatch=20))
    np.testing.assert_array_equal(cut.color, one.color)
    np.testing.assert_array_equal(cut.depth, one.depth)


def test_vulkan_renders_holdouts_as_the_cpu_reference():
    renderer = bvhlab.Renderer("vulkan", validation=True)
    scene = holdout_scene()
    bvh = bvhlab.build(scene)
    for film in (False, True):
        options = bvhlab.RenderOptions(samples_per_axis=N, max_depth=2, film_transparent=film)
        job = renderer.start(scene, bvh, W, H, options=options)
        job.run()
        vk = job.result()
        cpu = cpu_result(scene, bvh, options)
        assert (vk.color[..., 3] != cpu.color[..., 3]).mean() <= 0.01  # a ray grazing the sphere's rim
        diff = np.abs(vk.color - cpu.color)
        assert diff.mean() <= 1e-3 and (diff.max(-1) > 1e-3).mean() <= 0.01
        assert (vk.color[..., 3] == 0).sum() > 20
    assert renderer.validation_errors == 0, renderer.validation_messages()


def test_holdout_is_a_material_field_saved_with_the_scene(tmp_path):
    scene = holdout_scene()
    path = scene.save(tmp_path / "holdout.npz")
    loaded = bvhlab.Scene.load(path)
    assert [m.holdout for m in loaded.materials] == [m.holdout for m in scene.materials]
    assert loaded.materials[-1].holdout and not loaded.materials[0].holdout
    with pytest.raises(TypeError, match="holdout must be True or False"):
        bvhlab.Material(holdout=1)


def test_holdouts_in_a_two_level_scene():
    """Instances of a knot whose material is a holdout over a floor in mesh 0: the alpha of every
    pixel is the share of its camera rays that meet no knot (InstancedBvh.intersect over the
    tracer's own rays), on each walk of the CPU reference, and Vulkan's image is the CPU's."""
    from bvhlab.library import procedural

    floor, floor_material = showcase.checker_floor(6, 12.0)
    knot = procedural.torus_knot(2000)
    transforms = np.stack([np.eye(4, dtype=np.float32)[:3] for _ in range(3)])
    transforms[:, :, 3] = [(-2.5, 0, 1.2), (0, 1.5, 1.0), (2.5, 0, 1.4)]
    scene = bvhlab.Scene(
        triangles=floor,
        tri_material=floor_material,
        meshes=[knot],
        mesh_tri_material=[np.full(len(knot), 2, np.int32)],
        materials=[bvhlab.Material((0.9, 0.9, 0.85)), bvhlab.Material((0.3, 0.3, 0.3)), bvhlab.Material(holdout=True)],
        instance_mesh=np.array([1, 1, 1], np.int32),
        instance_transforms=transforms,
        camera=bvhlab.Camera((0.0, -9.0, 5.0), (0.0, 0.0, 1.0), fov_y=45.0),
    )
    tree = bvhlab.build(scene)
    assert isinstance(tree, bvhlab.InstancedBvh)
    options = bvhlab.RenderOptions(samples_per_axis=N)
    hit = camera_ray_hits(scene, tree, W, H, options)
    held = (hit["instance"] >= 0) & (scene.instance_mesh[hit["instance"]] == 1)
    alpha = (~held).mean(-1).astype(np.float32)
    assert (alpha == 0).sum() > 20 and ((alpha > 0) & (alpha < 1)).any()
    for traversal in ("stack", "stackless", "wide"):
        result = cpu_result(scene, tree, options.replace(traversal=traversal))
        np.testing.assert_array_equal(result.color[..., 3], alpha, err_msg=traversal)
    renderer = bvhlab.Renderer("vulkan", validation=True)
    job = renderer.start(scene, tree, W, H, options=options)
    job.run()
    vk, cpu = job.result(), cpu_result(scene, tree, options)
    assert (vk.color[..., 3] != cpu.color[..., 3]).mean() <= 0.01
    assert renderer.validation_errors == 0, renderer.validation_messages()


def test_the_cli_writes_a_holdouts_edges_with_straight_alpha(tmp_path):
    """`bvhlab render` of a scene file with a holdout, opaque film: the PNG's partly covered edge
    pixels hold the colour divided by alpha, as PNG stores it (they were written premultiplied,
    dark fringes, where only --film-transparent converted)."""
    from png_reader import read_png

    from bvhlab.cli import main
    from bvhlab.png import straight_alpha, to_rgba8

    scene = holdout_scene()
    path = scene.save(tmp_path / "holdout.npz")
    out = tmp_path / "holdout.png"
    args = ["--width", str(W), "--height", str(H), "--samples-per-axis", str(N), "--backend", "cpu"]
    assert main(["render", str(path), *args, "--out", str(out)]) == 0
    result = cpu_result(scene, bvhlab.build(scene), bvhlab.RenderOptions(samples_per_axis=N))
    edge = (result.color[..., 3] > 0) & (result.color[..., 3] < 1)
    assert edge.sum() > 5
    png = read_png(out).astype(int)
    expected = to_rgba8(straight_alpha(result.color)).astype(int)
    assert np.abs(png - expected)[edge].max() <= 1  # 8-bit rounding
