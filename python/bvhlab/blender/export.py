"""Blender scene → `bvhlab.Scene`: the one export path the add-on and the CLI share."""

from __future__ import annotations

from pathlib import Path

import bpy

from ..scene import Scene
from .live import LiveScene


def export_scene(
    context_or_scene=None,
    scope: str = "visible",
    depsgraph=None,
    *,
    require_camera: bool = True,
    instancing: bool = True,
    light_distance: float | None = None,
) -> Scene:
    """Export the evaluated scene (modifiers applied, world space) as a `bvhlab.Scene`.

    `context_or_scene`: a `bpy.types.Context`, a `bpy.types.Scene`, or None for `bpy.context`.
    `scope`: "visible" (every object visible in the view layer) or "selected".
    `depsgraph`: an evaluated depsgraph to read from (default: the view layer's).
    Objects flagged "Analytic sphere" become spheres, everything else triangles. Blender's
    instancing (collection, vertex, face and geometry-nodes instances, linked duplicates) becomes
    meshes stored once and instances of them (`instancing.py`; `Scene.flattened()` gives the world
    triangles); `instancing=False` places every instance's triangles into the world instead.
    `light_distance`: the distance the light's watts are calibrated by (light.py; None: measured,
    the median distance from the light to the exported primitives).
    Raises ExportError (a ValueError) for nothing in scope, a NaN vertex (naming the object), or no
    camera when `require_camera`. Otherwise a missing camera becomes one that frames the bounds
    and a missing light bvhlab's default light (SubstituteWarning), a missing world the default
    sky; approximations are reported as ExportWarning, all through `warnings`.
    """
    scene, view_layer = _scene_and_view_layer(context_or_scene)
    if depsgraph is None:
        depsgraph = view_layer.depsgraph or _evaluated(scene, view_layer)
        depsgraph.update()  # evaluates what changed since the last update; cheap when nothing did
    live = LiveScene(scope, require_camera=require_camera, instancing=instancing)  # a first sync reads everything
    live.light_distance = light_distance
    live.sync(depsgraph, scene, view_layer)
    assert live.scene is not None  # a sync either makes the scene or raises ExportError
    return live.scene


def export_scene_file(
    path,
    context_or_scene=None,
    scope: str = "visible",
    depsgraph=None,
    *,
    require_camera: bool = True,
    instancing: bool = True,
    light_distance: float | None = None,
) -> Scene:
    """Export like `export_scene` and write the `.npz` that `bvhlab.Scene.load` and the CLI read.
    Returns the exported Scene."""
    scene = export_scene(
        context_or_scene,
        scope,
        depsgraph,
        require_camera=require_camera,
        instancing=instancing,
        light_distance=light_distance,
    )
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


def _evaluated(scene, view_layer):
    """The depsgraph of a view layer Blender has not evaluated yet (another scene's, a layer just
    made: its `depsgraph` is None; the probe: AttributeError), evaluated as the context would."""
    with bpy.context.temp_override(scene=scene, view_layer=view_layer):
        return bpy.context.evaluated_depsgraph_get()
