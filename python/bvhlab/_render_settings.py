"""The typed settings of a render (`_core.RenderSettings`) from `bvhlab.render`'s arguments.
Types are checked here; values once, in C++."""

from __future__ import annotations

import numpy as np

from . import _checks, _core
from .bvh import Bvh
from .defaults import light_position
from .instanced import InstancedBvh
from .render_options import RenderOptions
from .scene import Camera, Scene, View
from .scene_parts import Light


def render_settings(
    scene: Scene, bvh: Bvh | InstancedBvh, width, height, options: RenderOptions, camera=None
) -> _core.RenderSettings:
    """The typed settings of a render: the scene's sky and light, the camera (default: the
    scene's), the size and the options. Types are checked here; values once, in C++ (ValueError)."""
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a bvhlab.Scene, got {type(scene).__name__}")
    if not isinstance(bvh, (Bvh, InstancedBvh)):
        raise TypeError(f"bvh must be a bvhlab.Bvh or bvhlab.InstancedBvh, got {type(bvh).__name__}")
    s = _core.RenderSettings()
    s.width, s.height = _checks.integer("width", width, 0, 2**31), _checks.integer("height", height, 0, 2**31)
    s.camera = _camera(scene, camera)
    _set_light(s, scene, camera)
    s.sky = scene.sky
    options.apply(s)
    s.validate()
    return s


def _camera(scene: Scene, camera) -> _core.Camera:
    camera = scene.camera if camera is None else camera
    if camera is None:  # nothing to frame: bvhlab.defaults' fallback camera
        from .defaults import camera_placement

        position, target, up, fov = camera_placement(scene.world_bounds())
        try:
            camera = Camera(position, target, up, fov)
        except ValueError as e:  # a scene reaching near ±MAX_COORDINATE: Scene left it without one
            raise ValueError(
                f"the default camera, which frames the whole scene, cannot be placed ({e}); "
                "give one: camera=bvhlab.Camera(position, look_at)"
            ) from None
    if not isinstance(camera, (Camera, View)):
        raise TypeError(f"camera must be a bvhlab.Camera or bvhlab.View, got {type(camera).__name__}")
    return camera.core()


def _set_light(s, scene: Scene, camera) -> None:
    light = scene.light
    if light is None:
        light = _default_light(s.camera, scene.camera if camera is None else camera)
    s.light.position, s.light.color, s.light.intensity = light.position, light.color, float(light.intensity)


def _default_light(look, given) -> Light:
    """The default light of a scene without one, for the camera the render uses (`look`, its
    _core.Camera; `given`, the Camera or View it was made from, None for the fallback): above and
    to the right of it (default_light_position). A Camera places it by the point it looks at; a
    View gives a direction only, so its light is placed as for the point one unit along it, in
    double precision: made from position + forward, a View's forward ×100 moved the light 100×
    as far (the same view, another picture), and far from the origin (a unit forward at 1e8) the
    two points were one in float32 and a valid View was refused as a camera looking at itself."""
    if isinstance(given, View):
        position, forward = np.asarray(look.position, np.float64), np.asarray(look.forward, np.float64)
        target = position + forward / np.linalg.norm(forward)
        return Light(light_position(tuple(position), tuple(target), tuple(look.up)))
    return Light(light_position(tuple(look.position), tuple(np.add(look.position, look.forward)), tuple(look.up)))
