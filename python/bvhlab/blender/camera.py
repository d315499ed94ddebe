"""The scene camera → `bvhlab.Camera` (pinhole: position, look-at, up, vertical field of view)."""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..scene import Camera
from .errors import ExportError, ExportWarning


def gather_camera(scene, depsgraph) -> Camera:
    """Position and orientation from the evaluated camera's world matrix (it looks along its -Z,
    its +Y is up; look_at is one unit ahead). The vertical field of view follows Blender's sensor
    fit for the render resolution's aspect ratio, so the picture frames what Blender's camera
    frames. Raises ExportError when there is no usable camera."""
    camera = scene.camera
    if camera is None:
        raise ExportError(f"scene '{scene.name}' has no camera: add one and make it the active camera")
    if camera.type != "CAMERA":
        raise ExportError(f"the scene camera '{camera.name}' is a {camera.type.lower()}, not a camera")
    evaluated = camera.evaluated_get(depsgraph)  # animation and drivers applied
    data = evaluated.data
    if data.type != "PERSP":
        raise ExportError(
            f"camera '{camera.name}' is {data.type.lower()}; bvhlab renders perspective (pinhole) cameras only"
        )
    if data.shift_x or data.shift_y:
        warnings.warn(f"camera '{camera.name}': lens shift is ignored", ExportWarning, stacklevel=2)
    matrix = np.array(evaluated.matrix_world, np.float64)
    position = matrix[:3, 3]
    z_length, y_length = np.linalg.norm(matrix[:3, 2]), np.linalg.norm(matrix[:3, 1])
    if not (np.isfinite(matrix).all() and z_length > 0 and y_length > 0):
        raise ExportError(
            f"camera '{camera.name}' has no usable orientation (a scale of 0, or a location, rotation "
            f"or scale that is not a number)"
        )
    forward, up = -matrix[:3, 2] / z_length, matrix[:3, 1] / y_length
    # look_at far enough ahead to differ from the position in float32 (the tracer's precision)
    ahead = max(1.0, float(np.abs(position).max()) * 2.0**-10)
    try:
        return Camera(tuple(position), tuple(position + forward * ahead), tuple(up), vertical_fov_degrees(scene, data))
    except ValueError as error:
        raise ExportError(f"camera '{camera.name}': {error}") from None


def vertical_fov_degrees(scene, camera_data) -> float:
    """Vertical field of view of a perspective camera for the scene's render aspect ratio."""
    render = scene.render
    aspect = (render.resolution_x * render.pixel_aspect_x) / (render.resolution_y * render.pixel_aspect_y)
    fit = camera_data.sensor_fit
    if fit == "AUTO":  # the sensor width spans the longer side of the picture
        fit = "HORIZONTAL" if aspect >= 1 else "VERTICAL"
        sensor = camera_data.sensor_width
    else:
        sensor = camera_data.sensor_width if fit == "HORIZONTAL" else camera_data.sensor_height
    half_tangent = sensor / (2 * camera_data.lens)
    if fit == "HORIZONTAL":
        half_tangent /= aspect
    return math.degrees(2 * math.atan(half_tangent))
