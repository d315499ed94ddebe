"""The typed settings of a render (`_core.RenderSettings`) from `bvhlab.render`'s arguments.
Types are checked here; values once, in C++."""

from __future__ import annotations

from . import _checks, _core
from .bvh import Bvh
from .instanced import InstancedBvh
from .render_options import RenderOptions
from .scene import Camera, Scene, View
from .scene_parts import default_light


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
    s.width, s.height = _checks.integer("width", width, 1, 2**31), _checks.integer("height", height, 1, 2**31)
    looking = _camera(scene, camera)
    s.camera = looking.core()
    light = scene.light if scene.light is not None else default_light(looking)
    s.light.position, s.light.color, s.light.intensity = light.position, light.color, float(light.intensity)
    s.sky = scene.sky
    options.apply(s)
    s.validate()
    return s


def default_camera(scene: Scene) -> Camera:
    """bvhlab.defaults' fallback camera, framing the scene; ValueError saying why where it cannot be
    placed (a scene reaching near ±MAX_COORDINATE, which Scene leaves without one)."""
    from .defaults import camera_placement

    position, target, up, fov = camera_placement(scene.world_bounds())
    try:
        return Camera(position, target, up, fov)
    except ValueError as e:
        raise ValueError(
            f"the default camera, which frames the whole scene, cannot be placed ({e}); "
            "give one: the scene's camera, or the render's camera=bvhlab.Camera(position, look_at)"
        ) from None


def _camera(scene: Scene, camera) -> Camera | View:
    """The Camera or View a render looks through: `camera`, else the scene's, else one framing it."""
    camera = scene.camera if camera is None else camera
    if camera is None:  # nothing to frame: bvhlab.defaults' fallback camera
        camera = default_camera(scene)
    if not isinstance(camera, (Camera, View)):
        raise TypeError(f"camera must be a bvhlab.Camera or bvhlab.View, got {type(camera).__name__}")
    return camera
