"""The 3D viewport's view as the camera the tracer takes, exactly: pure numpy on the region's
matrices (RegionView3D.view_matrix, window_matrix), so it is checked without a window.

Blender's projection for the region, off-centre or not (camera view panned or zoomed, lens
shift), perspective or orthographic, becomes a bvhlab.View with the same frustum: its field of
view, aspect, lens shift and clipping planes read from the window matrix. The traced image covers
the region pixel for pixel. Panoramic cameras are drawn by Blender's viewport as perspective ones,
and traced so (Cycles draws them panoramic in camera view; final renders here do too).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ViewFrustum:
    """A bvhlab.View for the region (`view`), the traced image size at full resolution, and the
    rectangle (x, y from the region's bottom left, width, height; pixels) the image covers in the
    region: all of it."""

    view: object
    width: int
    height: int
    draw_rect: tuple

    def camera(self):
        return self.view

    def scaled(self, scale: float) -> tuple[int, int]:
        """Image size at a fraction of full resolution (at least one pixel each way)."""
        return max(1, round(self.width * scale)), max(1, round(self.height * scale))


def view_frustum(view_matrix, window_matrix, region_width: int, region_height: int) -> ViewFrustum:
    """The frustum of a viewport region (see the module docstring). The window matrix is OpenGL's:
    NDC x = P00·tan + offset for a perspective view (tan = x / -z), P00·x + P03 orthographic; the
    clipping planes from its third row."""
    from bvhlab import View

    view, projection = np.asarray(view_matrix, np.float64), np.asarray(window_matrix, np.float64)
    to_world = np.linalg.inv(view)
    up, back = (to_world[:3, k] / np.linalg.norm(to_world[:3, k]) for k in (1, 2))
    forward, eye = -back, to_world[:3, 3]
    half_width, half_height = 1.0 / projection[0, 0], 1.0 / projection[1, 1]
    larger = 2 * max(half_width, half_height)
    # a camera view of a camera with left-handed axes (a scale of -1) shows the mirrored image
    lens: dict = {"aspect": half_width / half_height, "mirrored": bool(np.linalg.det(to_world[:3, :3]) < 0)}
    if projection[3, 3] == 0.0:  # perspective: clip w = -z
        centre = projection[0, 2] * half_width, projection[1, 2] * half_height
        near, far = projection[2, 3] / (projection[2, 2] - 1), projection[2, 3] / (projection[2, 2] + 1)
        lens["fov_y"] = math.degrees(2 * math.atan(half_height))
    else:
        centre = -projection[0, 3] * half_width, -projection[1, 3] * half_height
        near, far = (projection[2, 3] + 1) / projection[2, 2], (projection[2, 3] - 1) / projection[2, 2]
        lens.update(projection="orthographic", ortho_scale=larger)
        # the tracer's orthographic rays start on the camera's plane: put it on the near plane when
        # that lies behind the eye (a user orthographic view clips from -clip_end / 2)
        eye, far, near = eye + forward * min(near, 0.0), far - min(near, 0.0), max(near, 0.0)
    lens.update(shift_x=centre[0] / larger, shift_y=centre[1] / larger, clip_start=max(near, 0.0), clip_end=far)
    camera = View(tuple(eye), tuple(forward), tuple(up), **lens)
    return ViewFrustum(camera, region_width, region_height, (0, 0, region_width, region_height))
