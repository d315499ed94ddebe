"""Blender scene → `bvhlab.Scene`: the one export path the add-on and the CLI share."""
from __future__ import annotations

import warnings
from pathlib import Path

import bpy
import numpy as np

from ..scene import Scene
from .camera import gather_camera
from .errors import ExportError, SubstituteWarning
from .light import gather_light
from .material_table import MaterialTable
from .mesh import gather_mesh_triangles
from .scope import objects_in_scope
from .sphere import gather_sphere, is_analytic_sphere
from .world import gather_sky


def export_scene(context_or_scene=None, scope: str = "visible", depsgraph=None, *,
                 require_camera: bool = True) -> Scene:
    """Export the evaluated scene (modifiers applied, world space) as a `bvhlab.Scene`.

    `context_or_scene`: a `bpy.types.Context`, a `bpy.types.Scene`, or None for `bpy.context`.
    `scope`: "visible" (every object visible in the view layer) or "selected".
    `depsgraph`: an evaluated depsgraph to read from (default: the view layer's).
    Objects flagged "Analytic sphere" become spheres, everything else triangles.
    Raises ExportError (a ValueError) for nothing in scope, a NaN vertex (naming the object), or no
    camera when `require_camera`. Otherwise a missing camera becomes one that frames the bounds
    and a missing light bvhlab's default light (SubstituteWarning), a missing world the default
    sky; approximations are reported as ExportWarning, all through `warnings`.
    """
    scene, view_layer = _scene_and_view_layer(context_or_scene)
    if depsgraph is None:
        depsgraph = view_layer.depsgraph
        depsgraph.update()  # evaluates what changed since the last update; cheap when nothing did
    triangles, tri_material, spheres, sphere_material, table = _gather_geometry(depsgraph, view_layer, scope)
    try:
        camera = gather_camera(scene, depsgraph)
    except ExportError as error:
        if require_camera:
            raise
        camera = None  # the Scene frames its bounds
        warnings.warn(f"{error}; using a default camera that frames the geometry", SubstituteWarning, stacklevel=2)
    result = Scene(triangles=triangles, spheres=spheres, materials=table.materials, tri_material=tri_material,
                   sphere_material=sphere_material, camera=camera, sky=gather_sky(scene))
    light = gather_light(depsgraph, view_layer, _primitive_sample(result))
    if light is None:
        warnings.warn(f"scene '{scene.name}' has no visible light; using a default point light near the "
                      f"camera", SubstituteWarning, stacklevel=2)
    else:
        result.light = light
    return result


def export_scene_file(path, context_or_scene=None, scope: str = "visible", depsgraph=None, *,
                      require_camera: bool = True) -> Scene:
    """Export like `export_scene` and write the `.npz` that `bvhlab.Scene.load` and the CLI read.
    Returns the exported Scene."""
    scene = export_scene(context_or_scene, scope, depsgraph, require_camera=require_camera)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    scene.save(path)
    return scene


def _scene_and_view_layer(context_or_scene):
    if context_or_scene is None:
        context_or_scene = bpy.context
    if isinstance(context_or_scene, bpy.types.Scene):
        scene = context_or_scene
        active = bpy.context.view_layer
        return scene, active if bpy.context.scene == scene and active is not None else scene.view_layers[0]
    return context_or_scene.scene, context_or_scene.view_layer


def _gather_geometry(depsgraph, view_layer, scope: str):
    table = MaterialTable()
    triangle_parts, material_parts, spheres, sphere_material = [], [], [], []
    for obj, matrix, name in objects_in_scope(depsgraph, view_layer, scope):
        if obj.type == "MESH" and is_analytic_sphere(obj):
            spheres.append(gather_sphere(obj, matrix, name))
            sphere_material.append(table.slot_indices(obj)[0])
            continue
        triangles, slots = gather_mesh_triangles(obj, matrix, name)
        if len(triangles):
            triangle_parts.append(triangles)
            material_parts.append(table.map_slots(obj, slots))
    if not triangle_parts and not spheres:
        raise ExportError(_nothing_in_scope(scope))
    triangles = np.concatenate(triangle_parts) if triangle_parts else np.zeros((0, 3, 3), np.float32)
    tri_material = np.concatenate(material_parts) if material_parts else np.zeros(0, np.int32)
    spheres = np.array(spheres, np.float32).reshape(-1, 4)
    return triangles, tri_material, spheres, np.array(sphere_material, np.int32), table


def _primitive_sample(scene: Scene, size: int = 4096) -> np.ndarray:
    """Centres of about `size` primitives, evenly strided (deterministic), as float64 (N,3)."""
    triangles = scene.triangles[::max(1, len(scene.triangles) // size)].mean(axis=1)
    spheres = scene.spheres[::max(1, len(scene.spheres) // size), :3]
    return np.concatenate([triangles, spheres]).astype(np.float64)


def _nothing_in_scope(scope: str) -> str:
    if scope == "selected":
        return "no mesh in scope: no selected object has geometry (select meshes, or use scope 'visible')"
    return "no mesh in scope: no visible object has geometry (add a mesh or unhide one)"
