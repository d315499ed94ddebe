"""Blender's instancing exported as instances of one shared mesh (issue 34), under bpy 4.2.

Each scene is exported twice: as instances (the default) and flat (`instancing=False`: every
instance's triangles placed into the world, the export of before). The instanced scene's
flattening must hold the same world triangles (as a set, within float rounding; Scene.flattened()
keeps a mirrored mesh's winding, the flat export reverses it, so corners are compared as sets),
the shared meshes must be stored once, and F12 with the bvhlab engine (two-level tree) must give
the image and depth of bvhlab.render over the flat export's flat tree."""

import time

import blender_checks  # noqa: F401  (import path for the shared checks)
import bpy  # noqa: E402  (after harness)
import checks_engine  # noqa: E402
import harness  # before bpy
import numpy as np
import pytest
from blender_instance_scenes import SCENES, base_scene, collection_instances_scene, suzanne  # noqa: E402

import bvhlab  # noqa: E402
from bvhlab.blender import export_scene  # noqa: E402


@pytest.fixture(scope="module", autouse=True)
def addon_enabled():
    harness.enable_addon_from_source()


def _features(triangles: np.ndarray) -> np.ndarray:
    """Per triangle, what does not depend on the order of its corners: the centroid and the second
    moments of the corners (float64 (T,9))."""
    t = np.asarray(triangles, np.float64)
    centroid = t.mean(1)
    moments = np.einsum("tci,tcj->tij", t, t)[:, [0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]] / 3
    return np.concatenate([centroid, moments], 1)


def _match(got, expected, tolerance: float) -> np.ndarray:
    """For each triangle of `got` the index of a distinct triangle of `expected` with the same
    corners (within `tolerance`, in any order); fails naming the first without one."""
    a, b = _features(got), _features(expected)
    cell = 100 * tolerance
    cells: dict = {}
    for j, key in enumerate(map(tuple, np.floor(b[:, :3] / cell).astype(np.int64))):
        cells.setdefault(key, []).append(j)
    used = np.zeros(len(b), bool)
    out = np.empty(len(a), np.int64)
    offsets = [(x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1)]
    for i, key in enumerate(map(tuple, np.floor(a[:, :3] / cell).astype(np.int64))):
        near = [j for d in offsets for j in cells.get((key[0] + d[0], key[1] + d[1], key[2] + d[2]), ())]
        near = [j for j in near if not used[j] and np.abs(a[i] - b[j]).max() <= tolerance]
        assert near, f"triangle {i} {np.asarray(got)[i].tolist()} is not in the flat export"
        used[near[0]] = True
        out[i] = near[0]
    return out


@pytest.mark.parametrize("name", list(SCENES))
def test_instanced_export_flattens_to_the_flat_export(name):
    make, meshes, instances = SCENES[name]
    make()
    instanced = export_scene(bpy.context)
    flat = export_scene(bpy.context, instancing=False)
    assert instanced.is_instanced and not flat.is_instanced
    assert len(instanced.meshes) == meshes, [len(m) for m in instanced.meshes]
    shared = np.count_nonzero(instanced.instance_mesh > 0)
    assert shared == instances
    flattened = instanced.flattened()
    assert len(flattened.triangles) == len(flat.triangles)
    scale = max(1.0, float(np.abs(flat.triangles).max()))
    matched = _match(flattened.triangles, flat.triangles, 1e-5 * scale * scale)
    colors = np.array([m.color for m in flat.materials])[flat.tri_material[matched]]
    assert np.allclose(np.array([m.color for m in flattened.materials])[flattened.tri_material], colors)
    stored = len(instanced.triangles) + sum(len(m) for m in instanced.meshes)
    assert stored < len(flat.triangles), "an instanced mesh is stored more than once"


def _f12(tmp_path, scene, backend="cpu"):
    checks_engine.use_engine(scene, backend=backend, render_supersampling=1, render_overlay=False, render_bounces=3)
    got = checks_engine.render_passes(tmp_path)
    return got, checks_engine._last_final(scene)


def _render(tmp_path, scene):
    return checks_engine.render_passes(tmp_path), checks_engine._last_final(scene)


def _flattened_outward(scene) -> bvhlab.Scene:
    """Scene.flattened() with the winding of mirrored instances' triangles reversed (flattened()
    moves vertices only; the tracers keep a mirrored instance's outside out, as the flat export
    does by reversing the winding), so that the flat scene shades as Blender shows it."""
    flat = scene.flattened()
    mesh_of, transforms = scene.instances()
    mirrored = np.linalg.det(transforms[:, :, :3].astype(np.float64)) < 0
    per_instance = np.array([len(scene.mesh_triangles(int(k))) for k in mesh_of])
    reverse = np.repeat(mirrored, per_instance)
    triangles = flat.triangles.copy()
    triangles[reverse] = triangles[reverse][:, ::-1]
    flat.triangles = triangles
    return flat


def _flat_reference(scene, exported=None):
    """bvhlab.render, with F12's settings, of a flat scene over its flat tree: the flattening of
    the scene F12 exported (`exported`: its render depsgraph), or else the flat export."""
    flat = export_scene(bpy.context, instancing=False) if exported is None else _flattened_outward(exported)
    settings = scene.bvhlab
    width, height = scene.render.resolution_x, scene.render.resolution_y
    options = settings.render_options()
    job = bvhlab.Renderer("cpu").start(
        flat, bvhlab.build(flat, config=settings.build_config()), width, height, camera=flat.camera, options=options
    )
    job.run()
    result = job.result(color=True, depth=True, cost=False, heat=False)
    return {"combined": result.color, "depth": result.depth}


@pytest.mark.parametrize("name", list(SCENES))
def test_f12_of_instances_equals_the_flattened_render(tmp_path, name):
    scene = SCENES[name][0]()
    got, record = _f12(tmp_path, scene)
    assert record["tree"] == "built"
    tree = harness.addon().trees.cache.tree(harness.addon().trees.key_of(scene, "visible"))
    assert isinstance(tree.bvh, bvhlab.InstancedBvh), "F12 did not render the instanced scene two-level"
    assert record["scene"].is_instanced
    # F12's scene comes from the render depsgraph (which hides the children of vertex and face
    # instancers, where the viewport's shows them): its own flattening is the oracle
    reference = _flat_reference(scene, record["scene"])
    image, depth = reference["combined"], reference["depth"]
    diff = np.abs(got["Combined"] - image).max(-1)
    hit = depth < checks_engine.MISS_DEPTH
    assert 0.05 < hit.mean() < 0.98, hit.mean()
    assert (diff > 1e-3).mean() <= 0.01, f"{(diff > 1e-3).mean():.4f} of the pixels differ in colour"
    same_depth = np.abs(got["Depth"] - depth) <= 1e-4 * np.maximum(depth, 1.0)
    assert same_depth.mean() >= 0.99, f"only {same_depth.mean():.4f} of the pixels have the same depth"
    print(f"{name}: {(diff > 1e-3).sum()} of {diff.size} pixels differ in colour, {(~same_depth).sum()} in depth")


@pytest.mark.parametrize("name", ["collection_instances", "geometry_nodes"])
def test_f12_of_instances_on_vulkan_equals_the_flattened_cpu_render(tmp_path, name):
    """The same through the Vulkan tracer (lavapipe here; a GPU where there is one): the two-level
    walk in traverse.glsl against the CPU reference of the flat scene."""
    try:
        bvhlab.Renderer("vulkan")
    except bvhlab.VulkanUnavailable as error:
        pytest.skip(f"no Vulkan: {error}")
    scene = SCENES[name][0]()
    got, record = _f12(tmp_path, scene, backend="vulkan")
    assert record["backend"] == "vulkan" and record["scene"].is_instanced
    reference = _flat_reference(scene, record["scene"])
    diff = np.abs(got["Combined"] - reference["combined"])
    assert diff.mean() <= 1e-3 and (diff.max(-1) > 1e-3).mean() <= 0.01, (diff.mean(), diff.max())
    same_depth = np.abs(got["Depth"] - reference["depth"]) <= 1e-4 * np.maximum(reference["depth"], 1.0)
    assert same_depth.mean() >= 0.99, same_depth.mean()
    print(f"{name} on {record['device']}: {(diff.max(-1) > 1e-3).sum()} pixels differ in colour")


def test_rerender_moves_instances_and_reads_a_changed_mesh_once(tmp_path):
    """F12 with Persistent Data (the engine keeps its LiveScene and depsgraph): moving an instancer
    changes only its instances' transforms (no mesh read, the meshes' arrays kept, a new TLAS:
    "placed"); editing the shared mesh reads it once, not once per instance, and updates its tree
    in place; every image equals the flat reference's."""
    scene = collection_instances_scene()
    _, record = _f12(tmp_path, scene)  # selects the engine (changing its settings ends Persistent Data's engine)
    assert record["tree"] == "built"
    scene.render.use_persistent_data = True
    _, record = _render(tmp_path, scene)
    assert record["tree"] == "kept"  # a new engine: a full sync, the same arrays (equal), the same tree
    first, totals = _live_scene(), _copy(record["totals"])
    bpy.data.objects["Instance 1"].location.x += 1.0  # one instancer: its Suzanne and box move
    got, record = _render(tmp_path, scene)
    moved = _copy(record["totals"])
    assert (moved["objects_read"], moved["instances_moved"] - totals["instances_moved"]) == (totals["objects_read"], 2)
    assert record["sync"].placeable and record["tree"] == "placed", (record["sync"], record["tree"])
    second = _live_scene()
    assert all(a is b for a, b in zip(second.meshes, first.meshes)) and second.triangles is first.triangles
    changed = np.flatnonzero(np.abs(second.instance_transforms - first.instance_transforms).max((1, 2)) > 0)
    assert len(changed) == 2 and np.allclose(
        second.instance_transforms[changed, 0, 3] - 1.0, first.instance_transforms[changed, 0, 3]
    )
    _compare(got, _flat_reference(scene, record["scene"]))
    mesh = bpy.data.meshes["Monkey"]
    mesh.vertices[0].co.z += 0.25  # the shared mesh changes
    mesh.update()
    got, record = _render(tmp_path, scene)
    edited = _copy(record["totals"])
    assert edited["objects_read"] - moved["objects_read"] == 1, (moved, edited)
    assert record["tree"] == "refit"  # the shared mesh's tree updated in place (the scene's policy), the other kept
    third = _live_scene()
    monkey = next(k for k, m in enumerate(first.meshes) if len(m) == 968)
    assert not np.array_equal(third.meshes[monkey], first.meshes[monkey])
    assert third.meshes[1 - monkey] is first.meshes[1 - monkey], "the unchanged box mesh was read again"
    _compare(got, _flat_reference(scene, record["scene"]))
    scene.render.use_persistent_data = False


def _live_scene():
    """The exported scene of the engine's last final render (Persistent Data keeps the engine)."""
    return harness.addon().state.last_final[bpy.context.scene.session_uid]["scene"]


def _copy(totals) -> dict:
    return dict(vars(totals))


def _compare(got, reference) -> None:
    diff = np.abs(got["Combined"] - reference["combined"]).max(-1)
    assert (diff > 1e-3).mean() <= 0.01, f"{(diff > 1e-3).mean():.4f} of the pixels differ in colour"


def test_spheres_stay_spheres_and_zero_scale_instances_stay_in_the_world():
    """A collection of an analytic sphere and Suzanne, instanced four times, one of them at zero
    scale: the spheres are spheres of mesh 0 (four), Suzanne is one mesh with two instances, and
    the zero-scale one (its transform cannot be inverted) and one scaled by 1e-25 along x (its
    inverse beyond MAX_TRANSFORM_ENTRY) are placed in mesh 0 as flat triangles;
    the scene builds and renders two-level."""
    from bvhlab.blender import SPHERE_PROPERTY

    base_scene()
    source = bpy.data.collections.new("Source")
    monkey = suzanne()
    source.objects.link(monkey)
    ball = harness.add_box("Ball", (0.0, 0.0, 1.5), size=0.6)
    bpy.context.scene.collection.objects.unlink(ball)
    source.objects.link(ball)
    ball[SPHERE_PROPERTY] = True
    for i, scale in enumerate([(1.0, 1.0, 1.0), (0.5, 0.5, 0.5), (0.0, 1.0, 1.0), (1e-25, 1.0, 1.0)]):
        empty = bpy.data.objects.new(f"Instance {i}", None)
        empty.instance_type, empty.instance_collection = "COLLECTION", source
        bpy.context.scene.collection.objects.link(empty)
        empty.location, empty.scale = (3.0 * i - 3.0, 0.0, 0.0), scale
    bpy.context.view_layer.update()
    exported = export_scene(bpy.context)
    assert len(exported.spheres) == 4 and len(exported.meshes) == 1
    assert np.count_nonzero(exported.instance_mesh == 1) == 2
    assert len(exported.triangles) == 2 * 968  # the zero-scale and the 1e-25 Suzanne, flat
    assert np.allclose(sorted(exported.spheres[:, 3]), [0.15, 0.3, 0.3, 0.3], atol=1e-6)  # largest half extent
    bvh = bvhlab.build(exported)
    assert isinstance(bvh, bvhlab.InstancedBvh)
    image, _ = bvhlab.render(exported, bvh, 32, 24, backend="cpu")
    assert np.isfinite(image).all()


def test_a_thousand_instances_store_the_mesh_once():
    """1,000 collection instances of a 15,744-triangle Suzanne: one mesh, 1,000 transforms. The
    export time and bytes are printed (bench/export_instances.py measures them against the flat
    export); the test asserts what is stored."""
    scene = base_scene()
    source = bpy.data.collections.new("Source")
    source.objects.link(suzanne(subdivisions=2))
    for i in range(1000):
        empty = bpy.data.objects.new(f"Instance {i}", None)
        empty.instance_type, empty.instance_collection = "COLLECTION", source
        scene.collection.objects.link(empty)
        empty.location = (3.0 * (i % 40), 3.0 * (i // 40), 0.0)
    bpy.context.view_layer.update()
    start = time.perf_counter()
    exported = export_scene(bpy.context)
    seconds = time.perf_counter() - start
    assert len(exported.meshes) == 1 and len(exported.meshes[0]) == 15744 and len(exported.triangles) == 0
    assert len(exported.instance_mesh) == 1000
    stored = sum(m.nbytes for m in exported.meshes) + exported.instance_transforms.nbytes
    assert stored <= 15744 * 36 + 1000 * 48 + sum(m.nbytes for m in exported.mesh_tri_material)
    print(f"1,000 instances of 15,744 triangles: export {seconds * 1e3:.0f} ms, {stored / 1e6:.2f} MB stored")
