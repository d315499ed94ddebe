"""The 3D viewport's view as the camera the tracer takes, exactly: pure numpy on the region's
matrices (RegionView3D.view_matrix, window_matrix), so it is checked without a window.

Blender's projection for the region, off-centre or not (camera view panned or zoomed, lens
shift), perspective or orthographic, becomes a bvhlab.View with the same frustum: its field of
view, aspect, lens shift and clipping planes read from the window matrix. The traced image covers
the region pixel for pixel. Panoramic cameras are drawn by Blender's viewport as perspective ones,
and traced so (Cycles draws them panoramic in camera view; final renders here do too).
"""

from __future__ import annotations

import dataclasses
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

    def fitted(self, bounds):
        """The view for tracing a scene whose bounds `bounds()` gives ((lo, hi), or None when it has
        no geometry; called only for an orthographic view): its rays starting a little before the
        scene's bounds instead of on its near plane, which a user orthographic view puts
        clip_end / 2 behind the eye (with Clip End 1e7, 5e6 away, where float32 steps by 0.5: torn
        silhouettes; at 1e8 every object was lost). Nothing lies between the two planes, so the
        picture is the same; the clip range moves with the start. A scene wholly beyond the far
        plane keeps the view as it is (it shows nothing either way)."""
        view = self.view
        if view.projection != "orthographic":
            return view
        box = bounds()
        if box is None:
            return view
        lo, hi = (np.asarray(v, np.float64) for v in box)
        eye, forward = np.asarray(view.position), np.asarray(view.forward)
        corners = np.array([[(lo, hi)[(k >> a) & 1][a] for a in range(3)] for k in range(8)])
        margin = 0.05 * float(np.linalg.norm(hi - lo)) + 1e-3
        move = float(((corners - eye) @ forward).min()) - margin
        if not 0.0 < move < view.clip_end:  # the eye already at (or in) the scene; or all beyond clip_end
            return view
        return dataclasses.replace(
            view,
            position=tuple(eye + forward * move),
            clip_start=max(view.clip_start - move, 0.0),
            clip_end=view.clip_end - move,
        )

    def scaled(self, scale: float) -> tuple[int, int]:
        """Image size at a fraction of full resolution (at least one pixel each way)."""
        return max(1, round(self.width * scale)), max(1, round(self.height * scale))


def view_frustum(view_matrix, window_matrix, region_width: int, region_height: int, clip=None) -> ViewFrustum:
    """The frustum of a viewport region (see the module docstring). The window matrix is OpenGL's:
    NDC x = P00·tan + offset for a perspective view (tan = x / -z), P00·x + P03 orthographic; the
    clipping planes from its third row, or `clip` (start, end: view_clip's) where that row is the
    one they make in float32 (so a clip range from another source than Blender's is never taken).
    A far plane the matrix no longer holds (and no clip given) is left open."""
    from bvhlab import View

    view, projection = np.asarray(view_matrix, np.float64), np.asarray(window_matrix, np.float64)
    to_world = np.linalg.inv(view)
    up, back = (to_world[:3, k] / np.linalg.norm(to_world[:3, k]) for k in (1, 2))
    forward, eye = -back, to_world[:3, 3]
    half_width, half_height = 1.0 / projection[0, 0], 1.0 / projection[1, 1]
    larger = 2 * max(half_width, half_height)
    # a camera view of a camera with left-handed axes (a scale of -1) shows the mirrored image
    lens: dict = {"aspect": half_width / half_height, "mirrored": bool(np.linalg.det(to_world[:3, :3]) < 0)}
    perspective = projection[3, 3] == 0.0
    near, far = _clip_range(projection, perspective, clip)
    if perspective:  # clip w = -z
        centre = projection[0, 2] * half_width, projection[1, 2] * half_height
        lens["fov_y"] = math.degrees(2 * math.atan(half_height))
    else:
        centre = -projection[0, 3] * half_width, -projection[1, 3] * half_height
        lens.update(projection="orthographic", ortho_scale=larger)
        # the tracer's orthographic rays start on the camera's plane: put it on the near plane when
        # that lies behind the eye (a user orthographic view clips from -clip_end / 2); the
        # viewport moves it up to the scene's bounds (ViewFrustum.fitted), as far as clip_end allows
        eye, far, near = eye + forward * min(near, 0.0), far - min(near, 0.0), max(near, 0.0)
    lens.update(shift_x=centre[0] / larger, shift_y=centre[1] / larger, clip_start=max(near, 0.0), clip_end=far)
    camera = View(tuple(eye), tuple(forward), tuple(up), **lens)
    return ViewFrustum(camera, region_width, region_height, (0, 0, region_width, region_height))


def _clip_range(projection: np.ndarray, perspective: bool, clip) -> tuple[float, float]:
    """(near, far) of the window matrix's third row, or `clip` where that row is what it makes."""
    p22, p23 = projection[2, 2], projection[2, 3]
    if clip is not None:
        n, f = (float(v) for v in clip)
        if perspective:
            made = -(f + n) / (f - n), -2 * f * n / (f - n)
        else:
            made = -2 / (f - n), -(f + n) / (f - n)
        if f > n and all(
            np.isclose(np.float32(m), np.float32(p), rtol=1e-5, atol=1e-7) for m, p in zip(made, (p22, p23))
        ):
            return n, f
    if perspective:
        near, far = p23 / (p22 - 1), p23 / (p22 + 1) if p22 + 1 < 0 else math.inf
    else:
        near, far = (p23 + 1) / p22, (p23 - 1) / p22
    if not far > near:  # float32 rounding of a huge range: leave it open rather than trace nothing
        far = math.inf
    return float(near), float(far)


def view_clip(region_view, space, blender_scene) -> tuple[float, float] | None:
    """Blender's clip range for the region (its camera's in camera view, the view's own otherwise:
    -clip_end / 2 to clip_end / 2 in an orthographic user view), or None where it is not known
    here (a camera view through an object that is not a camera)."""
    if region_view.view_perspective == "CAMERA":
        camera = region_camera(space, blender_scene)
        if camera is None or camera.type != "CAMERA":
            return None
        return camera.data.clip_start, camera.data.clip_end
    if space is None:
        return None
    if region_view.view_perspective == "ORTHO":
        return -space.clip_end / 2, space.clip_end / 2
    return space.clip_start, space.clip_end


def region_camera(space, blender_scene):
    """The object a 3D view looks through in camera view: its local camera where it has one, else
    the scene's (None for neither)."""
    return (space.camera if space is not None and space.use_local_camera else None) or blender_scene.camera
