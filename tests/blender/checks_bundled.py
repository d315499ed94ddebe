"""Export checks on the bundled scenes, against scenes.json (what make_scenes.py built and Blender
evaluated) and against Blender's own numbers (mathutils transforms, view_frame, lights, world)."""

from __future__ import annotations

import math
import warnings

import bpy
import harness  # noqa: F401  (before bpy)
import numpy as np

from bvhlab.blender import SPHERE_PROPERTY, ExportWarning, export_scene


def export_bundled(name: str):
    """Open a bundled scene and export it; the export must not need to warn about anything. An
    instanced export (moving_ball's keyframed mesh ball is a mesh and an instance of its own:
    docs/design.md, "Blender's instancing") is checked flattened: the world triangles."""
    scene = harness.open_scene(name)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExportWarning)
        exported = export_scene(bpy.context)
    return scene, exported.flattened() if exported.is_instanced else exported


def check_counts(name: str, scene, exported) -> None:
    expected = harness.scenes_index()[name]
    assert len(exported.triangles) == expected["triangles"], (len(exported.triangles), expected["triangles"])
    assert len(exported.spheres) == expected["spheres"], (len(exported.spheres), expected["spheres"])


def _nearest_distance(points: np.ndarray, candidates: np.ndarray, within: float = 1e-3) -> np.ndarray:
    """Distance from each point to the nearest candidate (inf when none is within `within` in x)."""
    xs = candidates[:, 0]
    out = []
    for p in points:
        near = candidates[np.abs(xs - p[0]) <= within]  # one column first: a million rows stay cheap
        out.append(np.sqrt(((near - p) ** 2).sum(1).min()) if len(near) else np.inf)
    return np.array(out)


def check_world_positions(name: str, scene, exported) -> None:
    """Known world positions (scenes.json) are exported vertices or spheres, and evaluated vertices
    transformed by mathutils (obj.matrix_world @ co, not bvhlab's numpy) are exported vertices."""
    expected = harness.scenes_index()[name]["world_positions"]
    vertices = exported.triangles.reshape(-1, 3).astype(np.float64)
    if "spheres" in expected:
        for sphere in np.array(expected["spheres"]):
            assert np.abs(exported.spheres - sphere).max(1).min() < 1e-4, f"sphere {sphere} not exported"
    if "points" in expected:
        assert _nearest_distance(np.array(expected["points"], float), vertices).max() < 1e-4
    depsgraph = bpy.context.evaluated_depsgraph_get()
    for obj in scene.objects:
        if obj.type != "MESH" or obj.get(SPHERE_PROPERTY):
            continue
        mesh = obj.evaluated_get(depsgraph).data
        picks = np.linspace(0, len(mesh.vertices) - 1, 4).astype(int)
        world = np.array([tuple(obj.matrix_world @ mesh.vertices[int(i)].co) for i in picks])
        assert _nearest_distance(world, vertices).max() < 1e-4 * max(1.0, np.abs(world).max()), obj.name


def check_materials(name: str, scene, exported) -> None:
    """Every Principled material becomes (colour, reflective = metallic, transparent = transmission,
    IOR; no holdout, seen by every ray), and each primitive points at an existing material."""
    expected = harness.scenes_index()[name]["materials"]
    rows = exported.material_table().astype(np.float64)
    assert not rows[:, 6:].any(), rows  # no bundled scene has a holdout or a surface hidden from rays
    rows = rows[:, :6]  # scenes.json's six numbers a material
    for material, row in expected.items():
        assert np.abs(rows - np.array(row)).max(1).min() < 1e-5, f"material {material} {row} not in {rows}"
    used = np.union1d(exported.tri_material, exported.sphere_material)
    assert len(used) == len(expected), f"{len(used)} materials used, scenes.json lists {len(expected)}"


def check_camera(name: str, scene, exported) -> None:
    """Position and axes from the camera's world matrix; the vertical field of view from Blender's
    view_frame (which applies sensor fit and aspect itself)."""
    camera = scene.camera
    matrix = np.array(camera.matrix_world)
    np.testing.assert_allclose(exported.camera.position, matrix[:3, 3], atol=1e-5)
    forward = np.subtract(exported.camera.look_at, exported.camera.position)
    np.testing.assert_allclose(
        forward / np.linalg.norm(forward), -matrix[:3, 2] / np.linalg.norm(matrix[:3, 2]), atol=1e-6
    )
    np.testing.assert_allclose(exported.camera.up, matrix[:3, 1] / np.linalg.norm(matrix[:3, 1]), atol=1e-6)
    frame = np.array([tuple(v) for v in camera.data.view_frame(scene=scene)])
    fov_y = math.degrees(2 * math.atan(np.abs(frame[:, 1]).max() / abs(frame[0, 2])))
    assert abs(exported.camera.fov_y - fov_y) < 1e-4, (exported.camera.fov_y, fov_y)


def check_light_and_sky(name: str, scene, exported) -> None:
    """The first point light's position and colour; intensity = watts / (4π² d²) with d the median
    distance to the primitives (computed here over all of them; the export samples); the world's
    background colour × strength as the sky."""
    light = next(obj for obj in sorted(scene.objects, key=lambda o: o.name) if obj.type == "LIGHT")
    np.testing.assert_allclose(exported.light.position, tuple(light.matrix_world.translation), atol=1e-5)
    np.testing.assert_allclose(exported.light.color, tuple(light.data.color), atol=1e-6)
    centres = np.concatenate([exported.triangles.mean(1), exported.spheres[:, :3]])
    median = np.median(np.linalg.norm(centres - np.array(exported.light.position), axis=1))
    assert math.isclose(exported.light.intensity, light.data.energy / (4 * math.pi**2 * median**2), rel_tol=0.05)
    background = scene.world.node_tree.nodes["Background"].inputs
    sky = np.array(background["Color"].default_value[:3]) * background["Strength"].default_value
    np.testing.assert_allclose(exported.sky, sky, atol=1e-6)


BUNDLED_CHECKS = (check_counts, check_world_positions, check_materials, check_camera, check_light_and_sky)


def check_bundled_scene(name: str) -> None:
    """Open and export the scene once, then run every check above on it. The file must have been
    saved by the oldest supported Blender (4.2): 4.x cannot open files saved by 5.x."""
    scene, exported = export_bundled(name)
    assert tuple(bpy.data.version[:2]) <= (4, 2), f"{name} was saved by Blender {bpy.data.version}"
    for check in BUNDLED_CHECKS:
        check(name, scene, exported)


def check_large_export(name: str = "suzanne_1m") -> None:
    """A million evaluated triangles (Subdivision Surface level 5) export completely, twice in a
    row with the same result (the second from Blender's evaluated cache). Its speed is measured in
    bench/blender_export.py, not here."""
    harness.open_scene(name)
    first = export_scene(bpy.context)
    second = export_scene(bpy.context)
    assert len(first.triangles) == harness.scenes_index()[name]["triangles"] >= 1_000_000
    assert np.array_equal(first.triangles, second.triangles)
