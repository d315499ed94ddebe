"""The typed settings of a render (`_core.RenderSettings`) from `bvhlab.render`'s arguments.
Types are checked here; values once, in C++."""

from __future__ import annotations

import numbers

import numpy as np

from . import _checks, _core
from .bvh import Bvh
from .scene import Camera, Scene, View


def render_settings(
    scene: Scene,
    bvh: Bvh,
    width,
    height,
    *,
    camera=None,
    samples_per_axis=1,
    max_depth=5,
    overlay_depth=None,
    traversal=_core.DEFAULT_TRAVERSAL,
    mode="shade",
    color_by_depth=True,
    line_width=1.0,
    heatmap_scale=None,
    steps_per_dispatch=None,
    max_steps_per_pixel=None,
) -> _core.RenderSettings:
    """The typed settings of a render. Types are checked here; values once, in C++ (ValueError)."""
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a bvhlab.Scene, got {type(scene).__name__}")
    if not isinstance(bvh, Bvh):
        raise TypeError(f"bvh must be a bvhlab.Bvh, got {type(bvh).__name__}")
    s = _core.RenderSettings()
    s.width, s.height = _checks.integer("width", width, 0, 2**31), _checks.integer("height", height, 0, 2**31)
    s.samples_per_axis = _checks.integer("samples_per_axis", samples_per_axis, 0, 2**31)
    s.max_ray_depth = _checks.integer("max_depth", max_depth, 0, 2**31)
    s.camera = _camera(scene, camera)
    _set_light(s, scene, camera)
    s.sky = scene.sky
    _set_overlay(s, overlay_depth)
    s.overlay_color_by_depth = bool(color_by_depth)
    s.line_width = _real("line_width", line_width)
    s.traversal = _core.parse_traversal(_name("traversal", traversal))
    s.mode = _core.parse_render_mode(_name("mode", mode))
    s.heatmap_scale = None if heatmap_scale is None else _real("heatmap_scale", heatmap_scale)
    if steps_per_dispatch is not None:
        s.steps_per_dispatch = _checks.integer("steps_per_dispatch", steps_per_dispatch, 0, 2**31)
    if max_steps_per_pixel is not None:
        s.max_steps_per_pixel = _checks.integer("max_steps_per_pixel", max_steps_per_pixel, 0, 2**63)
    s.validate()
    return s


def _name(what: str, value) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{what} must be a string, got {type(value).__name__}")
    return value


def _real(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, got {type(value).__name__}")
    return float(value)


def _camera(scene: Scene, camera) -> _core.Camera:
    camera = scene.camera if camera is None else camera
    if camera is None:  # nothing to frame: bvhlab.defaults' fallback camera
        from .defaults import camera_placement

        position, target, up, fov = camera_placement(scene.bounds() if scene.primitive_count else None)
        camera = Camera(position, target, up, fov)
    if not isinstance(camera, (Camera, View)):
        raise TypeError(f"camera must be a bvhlab.Camera or bvhlab.View, got {type(camera).__name__}")
    return camera.core()


def _set_light(s, scene: Scene, camera) -> None:
    light = scene.light
    if light is None:
        from .scene import default_light

        look = s.camera
        light = default_light(Camera(tuple(look.position), tuple(np.add(look.position, look.forward)), tuple(look.up)))
    s.light.position, s.light.color, s.light.intensity = light.position, light.color, float(light.intensity)


def _set_overlay(s, overlay_depth) -> None:
    if overlay_depth is None:
        return
    if not isinstance(overlay_depth, (tuple, list)) or len(overlay_depth) != 2:
        raise TypeError(f"overlay_depth must be a pair (depth_min, depth_max) of tree depths, got {overlay_depth!r}")
    s.overlay = True
    s.overlay_depth_min = _checks.integer("overlay depth_min", overlay_depth[0], 0, 255)
    s.overlay_depth_max = _checks.integer("overlay depth_max", overlay_depth[1], 0, 255)
