"""The viewport's view and settings as one ViewRequest (UI thread, inside view_draw)."""

from __future__ import annotations

from .scene_tree import BuildSettings
from .settings import backend, trace_settings
from .view_camera import view_frustum
from .viewport import ViewRequest


def view_request(context, blender_scene) -> ViewRequest:
    region, view = context.region, context.region_data
    frustum = view_frustum(view.view_matrix, view.window_matrix, region.width, region.height)
    return ViewRequest(
        frustum,
        trace_settings(blender_scene, viewport=True),
        backend(blender_scene),
        BuildSettings.of(blender_scene),
        blender_scene.bvhlab.viewport_budget_ms,
        camera_view_note(view, context.space_data, blender_scene),
    )


def camera_view_note(view, space, blender_scene) -> str:
    """What the viewport does not show of the camera it looks through (F12 renders it), in words;
    empty elsewhere."""
    camera = (space.camera if space is not None and space.use_local_camera else None) or blender_scene.camera
    if view.view_perspective != "CAMERA" or camera is None or camera.type != "CAMERA":
        return ""
    data = camera.data
    if data.type == "PANO":
        return "F12 renders the panorama; the viewport shows Blender's perspective view of it"
    if data.dof.use_dof:
        return "F12 renders the depth of field; the viewport does not"
    return ""
