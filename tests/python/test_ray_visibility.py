"""Materials hidden from some rays (Material.hidden_from; Cycles' Object ▸ Visibility ▸ Ray
Visibility: Camera, Shadow, Glossy, Transmission): the rays of those kinds pass through the
surface as if it were not there, the others see it. Checked against independent images: a sphere
hidden from every ray renders as the scene without it, bit for bit; hidden from some, the pixels
whose camera rays all meet it are the full scene's and those none of whose rays meet it the
scene's without it (Bvh.intersect over the tracer's own camera rays says which); hidden from
the camera, each pixel's depth is what Bvh.intersect finds in the scene without it. On each walk
of the CPU reference (the wide walk leaves a ray whose nearest hit is hidden to the stack walk),
on Vulkan (lavapipe, validation on), cut into dispatches, in two-level scenes and in files."""

import dataclasses

import numpy as np
import pytest
from oracles import camera_ray_hits

import bvhlab
from bvhlab import Rays
from bvhlab.library import showcase

W, H, N = 48, 36, 2
TARGET = 2  # whitted's blue sphere (material 4): the mirror (sphere 0) reflects it
EVERY = Rays.CAMERA | Rays.SHADOW | Rays.REFLECTION | Rays.REFRACTION
TRAVERSALS = ("stack", "stackless", "wide")


def hidden_scene(hidden, target=TARGET):
    """whitted with sphere `target` in a copy of its material hidden from `hidden`."""
    scene = showcase.whitted()
    materials = list(scene.materials)
    own = scene.sphere_material[target]
    materials.append(dataclasses.replace(materials[own], hidden_from=hidden))
    sphere_material = scene.sphere_material.copy()
    sphere_material[target] = len(materials) - 1
    return dataclasses.replace(scene, materials=materials, sphere_material=sphere_material)


def without(target=TARGET):
    scene = showcase.whitted()
    keep = np.arange(len(scene.spheres)) != target
    return dataclasses.replace(scene, spheres=scene.spheres[keep], sphere_material=scene.sphere_material[keep])


def render(scene, options, backend="cpu", renderer=None):
    job = (renderer or bvhlab.Renderer(backend)).start(scene, bvhlab.build(scene), W, H, options=options)
    job.run()
    return job.result()


def meets_target(options, target=TARGET):
    """Per pixel: all of its camera rays meet the sphere, none does (Bvh.intersect, full scene)."""
    scene = showcase.whitted()
    hit = camera_ray_hits(scene, bvhlab.build(scene), W, H, options)
    on = (hit["kind"] == 1) & (hit["prim"] == target)
    return on.all(-1), ~on.any(-1)


@pytest.mark.parametrize("traversal", TRAVERSALS)
def test_hidden_from_every_ray_is_the_scene_without_it(traversal):
    options = bvhlab.RenderOptions(samples_per_axis=N, max_depth=3, traversal=traversal)
    got = render(hidden_scene(EVERY), options)
    want = render(without(), options)
    np.testing.assert_array_equal(got.color, want.color)
    np.testing.assert_array_equal(got.depth, want.depth)
    assert (np.abs(render(showcase.whitted(), options).color - want.color).max(-1) > 0.01).sum() > 40


def only(scene, kind):
    """`scene` whose secondary rays are of one kind: without transparency (reflection rays), or
    without reflective materials (refraction rays, and the reflections of total internal reflection)."""
    zero = {"reflection": "transparent", "refraction": "reflective"}[kind]
    return dataclasses.replace(scene, materials=[dataclasses.replace(m, **{zero: 0.0}) for m in scene.materials])


@pytest.mark.parametrize(
    "hidden, kind, max_depth",
    [
        (Rays.SHADOW, None, 0),  # camera and shadow rays only: its shadow gone, itself as before
        (Rays.SHADOW | Rays.REFLECTION, "reflection", 2),  # and not in the mirror
        (Rays.SHADOW | Rays.REFRACTION, "refraction", 3),  # and not through the glass
    ],
    ids=["shadow", "reflection", "refraction"],
)
@pytest.mark.parametrize("traversal", TRAVERSALS)
def test_hidden_from_the_secondary_rays(hidden, kind, max_depth, traversal):
    """The diffuse blue sphere hidden from every ray the scene sends but camera rays: where a
    pixel's camera rays all meet it, the pixel is the full scene's (a convex diffuse surface sends
    only shadow rays, which cannot meet it again); where none does, the scene's without it. Each
    kind's own bit matters: with it cleared, some of those pixels differ."""
    w, h = 3 * W, 3 * H
    options = bvhlab.RenderOptions(samples_per_axis=1, max_depth=max_depth, traversal=traversal)

    def scene_of(scene):
        return only(scene, kind) if kind else scene

    def image(scene):
        job = bvhlab.Renderer("cpu").start(scene, bvhlab.build(scene), w, h, options=options)
        job.run()
        return job.result()

    full = scene_of(showcase.whitted())
    hit = camera_ray_hits(full, bvhlab.build(full), w, h, options)
    on = ((hit["kind"] == 1) & (hit["prim"] == TARGET))[..., 0]
    got, seen, bare = image(scene_of(hidden_scene(hidden))), image(full), image(scene_of(without()))
    np.testing.assert_array_equal(got.color[on], seen.color[on])
    np.testing.assert_array_equal(got.color[~on], bare.color[~on])
    np.testing.assert_array_equal(got.depth, seen.depth)  # the camera sees it
    assert on.sum() > 80
    cleared = hidden & Rays.SHADOW if kind else Rays(0)  # the kind's own bit cleared (shadow: none hidden)
    other = image(scene_of(hidden_scene(cleared)))
    assert (np.abs(other.color - got.color).max(-1) > 0.01)[~on].sum() >= 8


@pytest.mark.parametrize("traversal", TRAVERSALS)
def test_hidden_from_the_camera(traversal):
    """Each pixel's depth is what Bvh.intersect finds with the tracer's camera rays in the scene
    without the sphere; the pixels none of whose rays meets it are the full scene's (it still
    casts its shadow and shows in the mirror)."""
    options = bvhlab.RenderOptions(samples_per_axis=1, max_depth=2, traversal=traversal)
    on, off = meets_target(options)
    got = render(hidden_scene(Rays.CAMERA), options)
    bare = without()
    hit = camera_ray_hits(bare, bvhlab.build(bare), W, H, options)
    np.testing.assert_array_equal(np.isfinite(hit["t"][..., 0]), got.depth < 1e9)
    np.testing.assert_array_equal(got.depth[on], render(bare, options).depth[on])
    full = render(showcase.whitted(), options)
    np.testing.assert_array_equal(got.color[off], full.color[off])
    assert on.sum() > 20 and not np.array_equal(got.color[on], full.color[on])


def test_a_trace_cut_into_many_dispatches_is_the_same():
    """A trace cut into dispatches of 16 steps equals one run (the ray's kind travels on the ray
    stack and in the state saved between dispatches; few of these cuts land inside a secondary
    ray's walk, so this is a check of the whole, not of that word)."""
    for hidden in (Rays.CAMERA, Rays.SHADOW | Rays.REFLECTION, Rays.REFRACTION):
        scene = hidden_scene(hidden)
        options = bvhlab.RenderOptions(samples_per_axis=N, max_depth=3, traversal="stack")
        one = render(scene, options)
        np.testing.assert_array_equal(render(scene, options.replace(steps_per_dispatch=16)).color, one.color)


def test_vulkan_renders_hidden_surfaces_as_the_cpu_reference():
    renderer = bvhlab.Renderer("vulkan", validation=True)
    for hidden in (Rays.CAMERA, Rays.SHADOW | Rays.REFLECTION, EVERY):
        scene = hidden_scene(hidden)
        options = bvhlab.RenderOptions(samples_per_axis=N, max_depth=3)
        cpu = render(scene, options)
        vk = render(scene, options, renderer=renderer)
        diff = np.abs(vk.color - cpu.color)
        assert diff.mean() <= 1e-3 and (diff.max(-1) > 1e-3).mean() <= 0.01, (hidden, diff.mean())
    assert renderer.validation_errors == 0, renderer.validation_messages()


def test_hidden_meshes_in_a_two_level_scene():
    """Instances of a knot hidden from every ray over a floor: the image of the scene without them,
    on each walk of the CPU reference and on Vulkan."""
    from bvhlab.library import procedural

    floor, floor_material = showcase.checker_floor(6, 12.0)
    knot = procedural.torus_knot(2000)
    transforms = np.stack([np.eye(4, dtype=np.float32)[:3] for _ in range(3)])
    transforms[:, :, 3] = [(-2.5, 0, 1.2), (0, 1.5, 1.0), (2.5, 0, 1.4)]
    materials = [bvhlab.Material((0.9, 0.9, 0.85)), bvhlab.Material((0.3, 0.3, 0.3))]

    def scene_of(knot_material, instances):
        return bvhlab.Scene(
            triangles=floor,
            tri_material=floor_material,
            meshes=[knot],
            mesh_tri_material=[np.full(len(knot), 2, np.int32)],
            materials=[*materials, knot_material],
            instance_mesh=np.ones(instances, np.int32),
            instance_transforms=transforms[:instances],
            camera=bvhlab.Camera((0.0, -9.0, 5.0), (0.0, 0.0, 1.0), fov_y=45.0),
        )

    hidden = scene_of(bvhlab.Material((0.9, 0.2, 0.2), hidden_from=EVERY), 3)
    seen = scene_of(bvhlab.Material((0.9, 0.2, 0.2)), 3)
    bare = scene_of(bvhlab.Material((0.9, 0.2, 0.2)), 0)
    options = bvhlab.RenderOptions(samples_per_axis=N, max_depth=2)
    want = render(bare, options)
    for traversal in TRAVERSALS:
        got = render(hidden, options.replace(traversal=traversal))
        np.testing.assert_array_equal(got.color, want.color, err_msg=traversal)
    assert (np.abs(render(seen, options).color - want.color).max(-1) > 0.01).sum() > 50
    renderer = bvhlab.Renderer("vulkan", validation=True)
    vk = render(hidden, options, renderer=renderer)
    assert np.abs(vk.color - want.color).mean() <= 1e-3
    assert renderer.validation_errors == 0, renderer.validation_messages()


def test_hidden_from_is_saved_with_the_scene_and_checked(tmp_path):
    scene = hidden_scene(Rays.CAMERA | Rays.REFRACTION)
    loaded = bvhlab.Scene.load(scene.save(tmp_path / "hidden.npz"))
    assert [m.hidden_from for m in loaded.materials] == [m.hidden_from for m in scene.materials]
    assert loaded.materials[-1].hidden_from == Rays.CAMERA | Rays.REFRACTION
    assert bvhlab.Material(hidden_from=3).hidden_from == Rays.CAMERA | Rays.SHADOW
    with pytest.raises(ValueError, match="hidden_from must be Rays flags"):
        bvhlab.Material(hidden_from=16)
    for bad in (True, 1.0, "camera"):
        with pytest.raises(TypeError, match="hidden_from must be Rays flags"):
            bvhlab.Material(hidden_from=bad)


def test_files_of_format_3_load_seen_by_every_ray_and_bad_bits_are_refused(tmp_path):
    scene = hidden_scene(Rays.CAMERA)
    path = scene.save(tmp_path / "v4.npz")
    with np.load(path) as f:
        arrays = dict(f)
    assert int(arrays["format_version"]) == 4 and arrays["materials"].shape[1] == 8
    old = dict(arrays, materials=arrays["materials"][:, :7], format_version=np.array(3))
    np.savez(tmp_path / "v3.npz", **old)
    assert all(m.hidden_from == Rays(0) for m in bvhlab.Scene.load(tmp_path / "v3.npz").materials)
    for bad in (16.0, 2.5, -1.0):
        materials = arrays["materials"].copy()
        materials[-1, 7] = bad
        np.savez(tmp_path / "bad.npz", **dict(arrays, materials=materials))
        with pytest.raises(ValueError, match="hidden rays must be Rays flags"):
            bvhlab.Scene.load(tmp_path / "bad.npz")
