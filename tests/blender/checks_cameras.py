"""Issue 33: the render engine frames what Blender frames. For each camera kind and setting, the
engine's Depth pass (F12 through Blender's pipeline, on the CPU reference and on Vulkan) equals
Cycles' Depth pass of the same scene — an independent renderer, at 1 sample with a box pixel
filter of width 0.01 (its ray through the pixel centre) and no denoising — on interior pixels to
0.2% relative, and hit or miss agrees on at least 99.5% of the interior pixels; the same for the
Rendered viewport's camera in camera view, where the viewport has the setting. The scene has a
rotated, non-uniformly scaled camera under a rotated and scaled parent, collection instances and
a linked duplicate. Also: depth of field against the thin-lens blur worked out here, motion blur
said, a huge F12 refused before Blender allocates it, and the size of a border's Render Result.
"""

from __future__ import annotations

import functools
import math

import bpy
import harness
import numpy as np
from checks_engine import ENGINE, MISS_DEPTH, render_passes

import bvhlab
from bvhlab.blender import export_scene

#: Relative depth error allowed on interior pixels, and the share of interior pixels whose hit or
#: miss must agree (issue 33).
DEPTH_TOLERANCE, COVERAGE = 2e-3, 0.995


def _look(obj, target) -> None:
    """Point a camera (its -Z, +Y up) at `target` in world space, whatever its parent."""
    from mathutils import Vector

    world = obj.matrix_world
    direction = Vector(target) - world.translation
    wanted = direction.to_track_quat("-Z", "Y")
    parent = obj.parent.matrix_world.to_quaternion() if obj.parent else None
    obj.rotation_mode = "QUATERNION"
    obj.rotation_quaternion = parent.inverted() @ wanted if parent else wanted


def camera_scene(resolution=(64, 48)):
    """A floor, a back wall, boxes, a collection instanced twice (once rotated and scaled) and a
    linked duplicate; the camera is rotated and scaled (non-uniformly) under a rotated, scaled
    parent, looking across the boxes at the wall."""
    scene = harness.empty_scene(resolution)
    _plane("Floor", [(-6, -12, 0), (6, -12, 0), (6, 8, 0), (-6, 8, 0)])
    _plane("Wall", [(-6, 8, 0), (6, 8, 0), (6, 8, 2.5), (-6, 8, 2.5)])
    harness.add_box("Box A", (-1.5, 0.0, 0.5), rotation=(0.0, 0.0, 0.4))
    harness.add_box("Box B", (1.2, 0.5, 0.6), size=1.2, scale=(1.0, 2.0, 1.0))
    duplicate = bpy.data.objects.new("Box A copy", bpy.data.objects["Box A"].data)  # a linked duplicate
    scene.collection.objects.link(duplicate)
    duplicate.location, duplicate.rotation_euler = (2.8, 3.0, 1.2), (0.3, 0.0, 0.7)
    _instances(scene)
    parent = bpy.data.objects.new("Rig", None)
    scene.collection.objects.link(parent)
    parent.location, parent.rotation_euler, parent.scale = (0.4, -8.5, 2.6), (0.1, -0.05, 0.2), (1.3, 1.3, 1.3)
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    camera.parent = parent
    camera.location, camera.scale = (0.2, 0.3, -0.1), (0.7, 0.5, 0.9)
    camera.data.lens = 30
    scene.camera = camera
    bpy.context.view_layer.update()
    _look(camera, (0.2, 2.0, 1.2))
    harness.add_point_light((2.0, -3.0, 5.0))
    bpy.context.view_layer.update()
    return scene


def _plane(name: str, corners) -> None:
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(corners, [], [(0, 1, 2, 3)])
    bpy.context.scene.collection.objects.link(bpy.data.objects.new(name, mesh))


def _instances(scene) -> None:
    crate = bpy.data.collections.new("Crate")
    for k, location in enumerate(((0.0, 0.0, 0.4), (0.9, 0.2, 0.9))):
        part = bpy.data.objects.new(f"Crate part {k}", bpy.data.objects["Box B"].data)
        crate.objects.link(part)
        part.location, part.scale = location, (0.5, 0.25, 0.6)
    for k, (location, rotation, scale) in enumerate(
        (((-3.5, 2.5, 0.0), (0, 0, 0), 1.0), ((3.0, -1.0, 0.0), (0.0, 0.0, 0.8), 1.4))
    ):
        empty = bpy.data.objects.new(f"Crate {k}", None)
        empty.instance_type, empty.instance_collection = "COLLECTION", crate
        empty.location, empty.rotation_euler, empty.scale = location, rotation, (scale,) * 3
        scene.collection.objects.link(empty)


# -- the settings compared, each applied to camera_scene() ------------------------------------------
def _perspective(scene, data):
    pass


def _portrait_vertical_fit(scene, data):
    scene.render.resolution_x, scene.render.resolution_y = 48, 64
    data.sensor_fit, data.sensor_height = "VERTICAL", 20.0


def _portrait_horizontal_fit(scene, data):
    scene.render.resolution_x, scene.render.resolution_y = 48, 64
    data.sensor_fit = "HORIZONTAL"


def _lens_shift(scene, data):
    data.shift_x, data.shift_y = 0.15, -0.1


def _mirrored(scene, data):
    """A scale of -1 on the camera's x: Blender and Cycles mirror the image (the probe's F12 and
    viewport were the unmirrored image: 392 of 3,072 pixels apart), its lens shift with it."""
    scene.camera.scale = (-0.7, 0.5, 0.9)
    data.shift_x = 0.12
    bpy.context.view_layer.update()


def _mirrored_y(scene, data):
    """A scale of -1 on the camera's y: the image upside down (mirrored, its up turned)."""
    scene.camera.scale = (0.7, -0.5, 0.9)
    data.shift_y = 0.1
    bpy.context.view_layer.update()


def _orthographic(scene, data):
    data.type, data.ortho_scale, data.sensor_fit = "ORTHO", 9.0, "VERTICAL"
    data.shift_x, data.shift_y = 0.05, 0.08


def _orthographic_portrait(scene, data):
    scene.render.resolution_x, scene.render.resolution_y = 40, 64
    data.type, data.ortho_scale = "ORTHO", 12.0


def _pixel_aspect(scene, data):
    scene.render.pixel_aspect_x = 2.0


def _pixel_aspect_y_shifted(scene, data):
    scene.render.pixel_aspect_y = 1.5
    data.shift_x = -0.1


def _resolution_percentage(scene, data):
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 130, 98, 50


def _border(scene, data, crop: bool = False):
    r = scene.render
    r.use_border, r.use_crop_to_border = True, crop
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = 0.2, 0.7, 0.3, 0.9


def _border_crop(scene, data):
    _border(scene, data, crop=True)


def _clipping(scene, data):
    data.clip_start, data.clip_end = 6.5, 11.0  # issue 39: clip_end 7.5 hit 49% of the pixels, Cycles 24%


def _equirectangular(scene, data):
    _panorama(data, "EQUIRECTANGULAR")
    data.latitude_min, data.latitude_max = math.radians(-60), math.radians(75)
    data.longitude_min, data.longitude_max = math.radians(-150), math.radians(120)


def _equirectangular_shifted(scene, data):
    _panorama(data, "EQUIRECTANGULAR")
    data.shift_x, data.shift_y, data.clip_end = 0.1, -0.05, 12.0


def _fisheye(scene, data):
    _panorama(data, "FISHEYE_EQUIDISTANT")
    data.fisheye_fov = math.radians(200)


def _equirectangular_inverted(scene, data):
    """Ranges from max to min (the image mirrored), as Blender takes them and Cycles renders them
    (refused before: a probe, 2026-12-07; a fisheye past 360 degrees and longitudes past ±180 are
    test_render_cameras.py's: this scene is too small in them for the comparison's interior)."""
    _panorama(data, "EQUIRECTANGULAR")
    data.latitude_min, data.latitude_max = math.radians(40), math.radians(-30)
    data.longitude_min, data.longitude_max = math.radians(60), math.radians(-50)


def _panorama(data, kind: str) -> None:
    """Blender 4.0 and later keep the panorama settings on the camera; earlier, Cycles did."""
    data.type = "PANO"
    (data if hasattr(data, "panorama_type") else data.cycles).panorama_type = kind


def _looking_through(scene, kind: str):
    """The scene camera an object of `kind` (an empty, a spot light of a 70° cone, a point light)
    where the camera is: Cycles renders through it with its default lens or the light's cone."""
    camera = scene.camera
    data = None if kind == "EMPTY" else bpy.data.lights.new(kind.title(), "POINT" if kind == "POINT" else "SPOT")
    if data is not None and data.type == "SPOT":
        data.spot_size = math.radians(70)
    stand_in = bpy.data.objects.new(f"Looking through {kind.lower()}", data)
    scene.collection.objects.link(stand_in)
    bpy.context.view_layer.update()
    stand_in.matrix_world = camera.matrix_world.copy()
    scene.camera = stand_in


def _empty_camera(scene, data):
    _looking_through(scene, "EMPTY")


def _spot_light_camera(scene, data):
    _looking_through(scene, "LIGHT")


def _point_light_camera(scene, data):
    _looking_through(scene, "POINT")


#: name → (setting, whether the Rendered viewport has it in camera view: the viewport traces the
#: region's own projection, so render borders, the resolution percentage and panoramas are F12's)
SETTINGS = {
    "perspective": (_perspective, True),
    "portrait_vertical_fit": (_portrait_vertical_fit, True),
    "portrait_horizontal_fit": (_portrait_horizontal_fit, True),
    "lens_shift": (_lens_shift, True),
    "mirrored": (_mirrored, True),
    "mirrored_y": (_mirrored_y, True),
    "orthographic": (_orthographic, True),
    "orthographic_portrait": (_orthographic_portrait, True),
    "pixel_aspect": (_pixel_aspect, True),
    "pixel_aspect_y_shifted": (_pixel_aspect_y_shifted, True),
    "resolution_percentage": (_resolution_percentage, False),
    "border": (_border, False),
    "border_crop": (_border_crop, False),
    "clipping": (_clipping, True),
    "equirectangular": (_equirectangular, False),
    "equirectangular_shifted": (_equirectangular_shifted, False),
    "fisheye": (_fisheye, False),
    "equirectangular_inverted": (_equirectangular_inverted, False),
    # Blender's viewport draws these with a 35 mm lens (BKE_camera_params_from_object), Cycles
    # renders them with 50 mm or the cone's: F12's
    "empty_camera": (_empty_camera, False),
    "spot_light_camera": (_spot_light_camera, False),
    "point_light_camera": (_point_light_camera, False),
}


# -- rendering and comparing ------------------------------------------------------------------------
def use_cycles_reference(scene) -> None:
    """Cycles as the reference renders: 1 sample, box filter of width 0.01 (the ray through the
    pixel centre), no denoising, CPU; the Depth pass on."""
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device, c.samples, c.use_adaptive_sampling, c.use_denoising = "CPU", 1, False, False
    c.pixel_filter_type, c.filter_width = "BOX", 0.01
    bpy.context.view_layer.use_pass_z = True


def use_engine(scene, backend: str) -> None:
    """The engine on `backend`, 1 sample per pixel, no overlay; the Depth pass on."""
    scene.render.engine = ENGINE
    scene.bvhlab.backend, scene.bvhlab.render_supersampling, scene.bvhlab.render_overlay = backend, 1, False
    bpy.context.view_layer.use_pass_z = True


def cycles_depth(tmp_dir, name: str) -> np.ndarray:
    """Cycles' Depth pass (use_cycles_reference)."""
    use_cycles_reference(bpy.context.scene)
    return render_passes(tmp_dir, f"{name}_cycles")["Depth"]


def engine_depth(tmp_dir, name: str, backend: str) -> np.ndarray:
    """The engine's Depth pass (F12 through Blender's pipeline), 1 sample per pixel."""
    use_engine(bpy.context.scene, backend)
    return render_passes(tmp_dir, f"{name}_{backend}")["Depth"]


def viewport_depth(scene) -> np.ndarray:
    """Depth of the camera the Rendered viewport traces in camera view, for a region the size of
    the render (Blender's camera projection for it, with the pixel aspect), on the CPU reference."""
    from checks_engine_viewport import _engine_module

    width, height = scene.render.resolution_x, scene.render.resolution_y
    depsgraph = bpy.context.evaluated_depsgraph_get()
    camera = scene.camera.evaluated_get(depsgraph)
    window = camera.calc_matrix_camera(
        depsgraph, x=width, y=height, scale_x=scene.render.pixel_aspect_x, scale_y=scene.render.pixel_aspect_y
    )
    view_matrix = np.array(camera.matrix_world.normalized().inverted())
    frustum = _engine_module("view_camera").view_frustum(view_matrix, np.array(window), width, height)
    exported = export_scene(bpy.context)
    job = bvhlab.Renderer("cpu").start(exported, bvhlab.build(exported), width, height, camera=frustum.camera())
    job.run()
    return job.result(color=False, cost=False).depth


def interior(depth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(pixels whose 3×3 neighbourhood is all hit or all miss in `depth`, those of them that are
    hit on a smooth surface: neighbours within 5% of the centre's depth). Image borders are out."""
    hit = depth < MISS_DEPTH * 0.5
    h, w = depth.shape
    same, smooth = np.zeros_like(hit), np.zeros_like(hit)
    centre = depth[1:-1, 1:-1]
    all_hit, all_miss, near = np.ones_like(centre, bool), np.ones_like(centre, bool), np.ones_like(centre, bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            d = depth[1 + dy : h - 1 + dy, 1 + dx : w - 1 + dx]
            all_hit &= d < MISS_DEPTH * 0.5
            all_miss &= d >= MISS_DEPTH * 0.5
            near &= np.abs(d - centre) <= 0.05 * centre
    same[1:-1, 1:-1] = all_hit | all_miss
    smooth[1:-1, 1:-1] = all_hit & near
    return same, smooth


def compare_depth(ours: np.ndarray, cycles: np.ndarray, what: str) -> str:
    """Asserts issue 33's agreement; returns a line of figures."""
    assert ours.shape == cycles.shape, f"{what}: {ours.shape} pixels, Cycles {cycles.shape}"
    same, smooth = interior(cycles)
    hit_cycles, hit_ours = cycles < MISS_DEPTH * 0.5, ours < MISS_DEPTH * 0.5
    assert 0.05 < hit_cycles.mean() < 0.95, f"{what}: the scene must show geometry and sky ({hit_cycles.mean():.2f})"
    assert smooth.sum() >= 100 and same.sum() >= 0.4 * same.size, f"{what}: too few interior pixels"
    coverage = (hit_cycles == hit_ours)[same].mean()
    relative = np.abs(ours - cycles)[smooth] / cycles[smooth]
    agree = (relative <= DEPTH_TOLERANCE).mean()
    line = (
        f"{what}: hits {hit_cycles.mean():.2f}, coverage agrees on {coverage:.4f} of {same.sum()} interior "
        f"pixels, depth within 0.2% on {agree:.4f} (median {np.median(relative):.1e}, max {relative.max():.1e})"
    )
    assert coverage >= COVERAGE, line
    assert agree == 1.0, line
    missed = ~hit_ours & ~hit_cycles  # 1e10 where a ray missed; 1e11 where Blender fills an uncropped border
    assert np.array_equal(ours[missed], cycles[missed]), f"{what}: a miss is not as deep as Cycles writes it"
    return line


def _fresh(setting):
    scene = camera_scene()
    setting(scene, scene.camera.data)
    bpy.context.view_layer.update()
    return scene


def _cycles_reference(tmp_dir, name: str, scene) -> np.ndarray:
    """Cycles' Depth pass of the scene's camera; an empty as the camera under Blender 5.1 and 5.2,
    whose Cycles crashes rendering through one (a segfault, measured; Workbench and EEVEE render it
    with Blender's 35 mm, as 5.3's Cycles does), through a camera of the lens bvhlab gives it
    (compat.NON_CAMERA_LENS_MM) in its place: there the check tests the framing with that lens,
    not the lens itself (no Cycles of those versions can say which)."""
    from bvhlab.blender.compat import NON_CAMERA_LENS_MM

    stand_in = scene.camera
    if stand_in.type != "EMPTY" or not (5, 1, 0) <= bpy.app.version < (5, 3, 0):
        return cycles_depth(tmp_dir, name)
    data = bpy.data.cameras.new("In the empty's place")
    data.lens = NON_CAMERA_LENS_MM
    data.clip_start, data.clip_end = 1e-5, 1e5  # Cycles' for an object that is not a camera
    camera = bpy.data.objects.new("In the empty's place", data)
    scene.collection.objects.link(camera)
    camera.matrix_world = stand_in.matrix_world.copy()
    scene.camera = camera
    try:
        return cycles_depth(tmp_dir, name)
    finally:
        scene.camera = stand_in


def check_setting_against_cycles(tmp_dir, name: str) -> None:
    """One setting of SETTINGS: F12 on each backend there is, and the viewport's camera where it has
    the setting, against Cycles' Depth pass."""
    setting, in_viewport = SETTINGS[name]
    scene = _fresh(setting)
    reference = _cycles_reference(tmp_dir, name, scene)
    lines = [
        compare_depth(engine_depth(tmp_dir, name, backend), reference, f"{name} F12 {backend}")
        for backend in vulkan_backends()
    ]
    if in_viewport:
        lines.append(compare_depth(viewport_depth(scene), reference, f"{name} viewport"))
    print("cameras against Cycles:\n  " + "\n  ".join(lines))


@functools.cache
def vulkan_backends() -> tuple[str, ...]:
    """("cpu", "vulkan") where a Vulkan device is there, else ("cpu",)."""
    try:
        bvhlab.Renderer("vulkan")
    except bvhlab.VulkanUnavailable:
        return ("cpu",)
    return ("cpu", "vulkan")
