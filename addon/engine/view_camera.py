"""The 3D viewport's view as a camera the tracer takes (a symmetric pinhole), and where its image
goes in the region. Pure numpy on the region's matrices (RegionView3D.view_matrix, window_matrix),
so it is checked without a window.

The viewport's projection can be off-centre (camera view panned or zoomed, lens shift): the pinhole
frustum is then the smallest symmetric one that covers the region, traced at the region's pixel
density, and drawn shifted so the region shows its part. Orthographic views are traced by a pinhole
ORTHO_DISTANCE view heights behind the view's focal plane (perspective distortion across a depth
of one view height: 1/ORTHO_DISTANCE).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

ORTHO_DISTANCE = 500.0


@dataclass(frozen=True)
class ViewFrustum:
    """A bvhlab camera for the view (position, look_at, up, fov_y), the traced image size at full
    resolution, and the rectangle (x, y from the region's bottom left, width, height; pixels) the
    image covers in the region."""

    position: tuple
    look_at: tuple
    up: tuple
    fov_y: float
    width: int
    height: int
    draw_rect: tuple

    def camera(self):
        from bvhlab import Camera

        return Camera(self.position, self.look_at, self.up, self.fov_y)

    def scaled(self, scale: float) -> tuple[int, int]:
        """Image size at a fraction of full resolution (at least one pixel each way)."""
        return max(1, round(self.width * scale)), max(1, round(self.height * scale))


def view_frustum(
    view_matrix,
    window_matrix,
    region_width: int,
    region_height: int,
    perspective: bool = True,
    view_distance: float = 10.0,
) -> ViewFrustum:
    """The frustum of a viewport region (see the module docstring)."""
    view, projection = np.asarray(view_matrix, np.float64), np.asarray(window_matrix, np.float64)
    to_world = np.linalg.inv(view)
    right, up, back = (to_world[:3, k] / np.linalg.norm(to_world[:3, k]) for k in range(3))
    forward = -back
    eye = to_world[:3, 3]
    # Along each axis the region's NDC is s·t + c, t the tangent x/-z (perspective: c = -P[0][2]
    # as clip w = -z) or, orthographic, the view-space x over the pinhole's distance (c = P[0][3]).
    if perspective:
        sx, cx, sy, cy = projection[0, 0], -projection[0, 2], projection[1, 1], -projection[1, 2]
        position = eye
    else:
        half_height = 1.0 / projection[1, 1]
        distance = ORTHO_DISTANCE * half_height
        sx, cx = projection[0, 0] * distance, projection[0, 3]
        sy, cy = projection[1, 1] * distance, projection[1, 3]
        position = eye + forward * (view_distance - distance)
    width, x0 = _symmetric_span(sx, cx, region_width)
    height, y0 = _symmetric_span(sy, cy, region_height)
    tan_half_y = height / (sy * region_height)
    return ViewFrustum(
        tuple(position),
        tuple(position + forward),
        tuple(up),
        math.degrees(2 * math.atan(tan_half_y)),
        width,
        height,
        (x0, y0, width, height),
    )


def _symmetric_span(scale: float, centre: float, pixels: int) -> tuple[int, float]:
    """(traced pixels, region position of the traced image's first pixel) along one axis: the
    narrowest span symmetric about the view axis that covers the region, at the region's density."""
    half = max(abs((-1 - centre) / scale), abs((1 - centre) / scale))  # half extent in tangent units
    traced = max(1, round(half * scale * pixels))
    half = traced / (scale * pixels)  # exactly `traced` region pixels wide
    return traced, (1 + centre - half * scale) * pixels / 2
