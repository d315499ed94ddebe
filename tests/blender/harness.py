"""Shared set-up for the Blender checks, under pytest (bpy as a module) and under a Blender binary
(tests/blender/run.py): a private user-resources folder, the add-on enabled from source or from
the built zip, the bundled scenes, and small scenes made on the spot.

Import this before bpy: Blender reads BLENDER_USER_RESOURCES once, when it starts.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

if "bpy" not in sys.modules:  # a Blender binary has started already and set its own
    os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="bvhlab_blender_user_"))

import bpy  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCENES_DIR = ROOT / "blender_scenes"
ADDON_DIR = ROOT / "addon"
EXTENSION_ID = "bvhlab"
DEV_REPO = "bvhlab_dev"

_addon_module: str | None = None


def exit_without_teardown(code: int) -> None:
    """End a bpy-as-a-module process with `code`, skipping the interpreter's teardown: bpy 4.2 as a
    module segfaults while the interpreter shuts down once any Panel class has been registered
    (SpaceType's destructor frees the class after the interpreter is gone: a five-line script
    registering one Panel does it) or a shader made with gpu.shader.create_from_info has existed.
    Blender's teardown, not bvhlab's code; everything has run and reported by then."""
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def scenes_index() -> dict:
    """blender_scenes/scenes.json: name → file, description, counts, materials, world positions."""
    return json.loads((SCENES_DIR / "scenes.json").read_text())


def open_scene(name: str):
    """Open a bundled scene; returns bpy.context.scene."""
    bpy.ops.wm.open_mainfile(filepath=str(SCENES_DIR / scenes_index()[name]["file"]), load_ui=False)
    return bpy.context.scene


def enable_addon_from_source() -> str:
    """Enable addon/ in place through an extension repository whose folder links to it (the way
    Blender loads an installed extension, without building the zip). Returns the module name."""
    global _addon_module
    if _addon_module is None:
        repo_dir = Path(tempfile.mkdtemp(prefix="bvhlab_dev_repo_"))
        (repo_dir / EXTENSION_ID).symlink_to(ADDON_DIR, target_is_directory=True)
        bpy.context.preferences.extensions.repos.new(
            name=DEV_REPO, module=DEV_REPO, custom_directory=str(repo_dir), source="USER"
        )
        _addon_module = f"bl_ext.{DEV_REPO}.{EXTENSION_ID}"
    enable(_addon_module)
    return _addon_module


def enable(module: str) -> None:
    global _addon_module
    if module not in bpy.context.preferences.addons:
        bpy.ops.preferences.addon_enable(module=module)
    _addon_module = module


def addon():
    """The enabled add-on's package (for its state: the cached trees, messages...)."""
    return sys.modules[_addon_module]


def empty_scene(resolution=(64, 48)):
    """An empty file with a world colour and a small render resolution. (read_homefile, not
    read_factory_settings: that would also reset the preferences and so disable the add-on.)"""
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = resolution
    scene.render.resolution_percentage = 100
    scene.world = bpy.data.worlds.new("World")
    scene.world.color = (0.2, 0.3, 0.5)
    return scene


def add_box(name, location, size=1.0, rotation=(0.0, 0.0, 0.0), scale=(1.0, 1.0, 1.0)):
    """A cube mesh object (8 vertices at ±size/2) with a transform."""
    half = size / 2
    vertices = [(x, y, z) for x in (-half, half) for y in (-half, half) for z in (-half, half)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices, [], faces)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.location, obj.rotation_euler, obj.scale = location, rotation, scale
    return obj


def add_camera(location, target, lens=35.0):
    from mathutils import Vector

    obj = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    obj.data.lens = lens
    bpy.context.scene.collection.objects.link(obj)
    obj.location = location
    obj.rotation_euler = (Vector(target) - Vector(location)).to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.camera = obj
    return obj


def add_point_light(location, watts=1000.0, color=(1.0, 1.0, 1.0)):
    obj = bpy.data.objects.new("Light", bpy.data.lights.new("Light", "POINT"))
    obj.data.energy, obj.data.color = watts, color
    bpy.context.scene.collection.objects.link(obj)
    obj.location = location
    return obj


def boxes_scene():
    """Three transformed cubes in front of a camera, with a light: small and quick everywhere."""
    scene = empty_scene()
    add_box("Box A", (-1.5, 0.0, 0.5), rotation=(0.0, 0.0, 0.4))
    add_box("Box B", (1.2, 0.5, 0.6), size=1.2, scale=(1.0, 2.0, 1.0))
    add_box("Box C", (0.0, 2.0, 1.8), size=0.8, rotation=(0.3, 0.2, 0.0))
    add_camera((0.0, -8.0, 3.0), (0.0, 0.5, 0.8), lens=30)
    add_point_light((2.0, -3.0, 5.0))
    bpy.context.view_layer.update()
    return scene
