"""Small helpers for make_scenes.py: materials, camera, light, modifiers, counting, saving (bpy)."""

from __future__ import annotations

import math
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

from bvhlab.blender import SPHERE_PROPERTY
from bvhlab.blender.compat import ensure_shader_tree


def reset(sky=(0.55, 0.7, 0.9), resolution=(800, 600)):
    """An empty file with a world colour and the render resolution the report used (800×600)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = resolution
    scene.render.resolution_percentage = 100
    world = bpy.data.worlds.new("World")
    background = ensure_shader_tree(world).nodes["Background"]
    background.inputs["Color"].default_value = (*sky, 1.0)
    background.inputs["Strength"].default_value = 1.0
    world.color = sky
    scene.world = world
    return scene


def material(name, color, metallic=0.0, transmission=0.0, ior=1.45, roughness=0.4):
    """A Principled BSDF material; also returns what bvhlab should read from it (for scenes.json)."""
    mat = bpy.data.materials.new(name)
    bsdf = ensure_shader_tree(mat).nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Transmission Weight"].default_value = transmission
    bsdf.inputs["IOR"].default_value = ior
    bsdf.inputs["Roughness"].default_value = roughness
    mat.diffuse_color = (*color, 1.0)
    return mat


def link(obj):
    bpy.context.scene.collection.objects.link(obj)
    return obj


def mesh_object(name, vertices, faces, materials=(), location=(0, 0, 0)):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(map(float, v)) for v in vertices], [], [tuple(map(int, f)) for f in faces])
    mesh.update()
    for mat in materials:
        mesh.materials.append(mat)
    obj = link(bpy.data.objects.new(name, mesh))
    obj.location = location
    return obj


def box(name, lo, hi, materials=()):
    """An axis-aligned box (6 quads) with its origin at its centre."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    half = (hi - lo) / 2
    corners = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)] * half
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return mesh_object(name, corners, faces, materials, location=(lo + hi) / 2)


def uv_sphere(name, location, radius, mat, segments=32, rings=16, analytic=True, mesh=None):
    """A sphere object; `analytic` flags it so bvhlab exports one exact sphere. `mesh` shares data."""
    if mesh is None:
        bpy.ops.mesh.primitive_uv_sphere_add(segments=segments, ring_count=rings, radius=1.0)
        obj = bpy.context.object
        obj.data.materials.append(mat)
    else:
        obj = link(bpy.data.objects.new(name, mesh))
        obj.material_slots[0].link = "OBJECT"
        obj.material_slots[0].material = mat
    obj.name = name
    obj.location = location
    obj.scale = (radius,) * 3
    if analytic:
        obj[SPHERE_PROPERTY] = True
    return obj


def animate(obj, path, keys: dict):
    """Keyframes {frame: value} on a property of `obj`, interpolated linearly."""
    for frame, value in keys.items():
        setattr(obj, path, value)
        obj.keyframe_insert(path, frame=frame)
    for curve in obj.animation_data.action.fcurves:
        for point in curve.keyframe_points:
            point.interpolation = "LINEAR"


def modifier(obj, kind, **settings):
    mod = obj.modifiers.new(kind.title(), kind)
    for key, value in settings.items():
        setattr(mod, key, value)
    return mod


def array(obj, count, offset):
    return modifier(
        obj, "ARRAY", count=count, use_relative_offset=False, use_constant_offset=True, constant_offset_displace=offset
    )


def subdivide(obj, levels, simple=False):
    return modifier(
        obj, "SUBSURF", levels=levels, render_levels=levels, subdivision_type="SIMPLE" if simple else "CATMULL_CLARK"
    )


def camera(location, target, lens=35.0):
    data = bpy.data.cameras.new("Camera")
    data.lens = lens
    obj = link(bpy.data.objects.new("Camera", data))
    obj.location = location
    obj.rotation_euler = (Vector(target) - Vector(location)).to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.camera = obj
    return obj


def point_light(location, watts, color=(1.0, 1.0, 1.0), radius=0.1):
    data = bpy.data.lights.new("Light", "POINT")
    data.energy, data.color, data.shadow_soft_size = watts, color, radius
    obj = link(bpy.data.objects.new("Light", data))
    obj.location = location
    return obj


def counts(scene):
    """(triangles, spheres) the scene should export, counted from Blender's own evaluated loop
    triangles, independently of bvhlab's exporter."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    triangles = spheres = 0
    for obj in scene.objects:
        if obj.type != "MESH" or not obj.visible_get():
            continue
        if obj.get(SPHERE_PROPERTY):
            spheres += 1
            continue
        mesh = obj.evaluated_get(depsgraph).data
        mesh.calc_loop_triangles()
        triangles += len(mesh.loop_triangles)
    return triangles, spheres


def material_rows(scene):
    """What each Principled material in use should become: colour, reflective, transparent, IOR."""
    rows = {}
    for obj in scene.objects:
        for slot in obj.material_slots:
            inputs = slot.material.node_tree.nodes["Principled BSDF"].inputs
            rows[slot.material.name] = [
                *[round(c, 6) for c in inputs["Base Color"].default_value[:3]],
                inputs["Metallic"].default_value,
                inputs["Transmission Weight"].default_value,
                inputs["IOR"].default_value,
            ]
    return rows


def save(path: Path):
    """Save compressed, without unused data blocks, and without a .blend1 backup of the old file.
    Run with the oldest supported Blender (the project's .venv has bpy 4.2): newer versions read
    its files, but 4.x cannot open a file saved by 5.x."""
    if bpy.app.version[:2] != (4, 2):
        raise SystemExit(
            f"save the bundled scenes with bpy 4.2 (the oldest supported Blender), not {bpy.app.version_string}"
        )
    bpy.context.preferences.filepaths.save_version = 0
    bpy.data.orphans_purge(do_recursive=True)
    bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=True, relative_remap=False)


def arch(name, inner, outer, depth, segments, materials=()):
    """A semicircular arch in the XZ plane (origin at the centre of its springing line), `depth`
    thick along Y: front, back, outer and inner faces, and the two ends."""
    theta = np.linspace(0.0, math.pi, segments + 1)
    vertices = [
        (r * math.cos(t), y, r * math.sin(t)) for r in (inner, outer) for y in (-depth / 2, depth / 2) for t in theta
    ]
    n = segments + 1

    def at(layer, side, i):  # layer 0 inner / 1 outer, side 0 front / 1 back
        return (2 * layer + side) * n + i

    faces = []
    for i in range(segments):
        faces.append((at(0, 0, i), at(1, 0, i), at(1, 0, i + 1), at(0, 0, i + 1)))  # front
        faces.append((at(0, 1, i + 1), at(1, 1, i + 1), at(1, 1, i), at(0, 1, i)))  # back
        faces.append((at(1, 0, i), at(1, 1, i), at(1, 1, i + 1), at(1, 0, i + 1)))  # outer
        faces.append((at(0, 0, i + 1), at(0, 1, i + 1), at(0, 1, i), at(0, 0, i)))  # inner
    for i in (0, segments):  # ends, standing on the capitals
        faces.append((at(0, 0, i), at(0, 1, i), at(1, 1, i), at(1, 0, i)))
    return mesh_object(name, vertices, faces, materials)
