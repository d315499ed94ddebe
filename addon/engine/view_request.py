"""The viewport's view and settings as one ViewRequest (UI thread, inside view_draw)."""

from __future__ import annotations

from ..trees import key_of, update_config
from .counter_view import counter_view
from .settings import backend
from .view_camera import region_camera, view_clip, view_frustum
from .viewport import ViewRequest


def view_request(context, blender_scene) -> ViewRequest:
    region, view = context.region, context.region_data
    clip = view_clip(view, context.space_data, blender_scene)
    frustum = view_frustum(view.view_matrix, view.window_matrix, region.width, region.height, clip)
    return ViewRequest(
        frustum,
        blender_scene.bvhlab.render_options(viewport=True),
        backend(blender_scene),
        key_of(blender_scene, scope="visible"),  # the viewport shows every visible object
        blender_scene.bvhlab.viewport_budget_ms,
        camera_view_note(view, context.space_data, blender_scene),
        update_config(blender_scene),
        counter_view(blender_scene.bvhlab),
    )


def camera_view_note(view, space, blender_scene) -> str:
    """What the viewport does not show of the camera it looks through (F12 renders it), in words;
    empty elsewhere."""
    if view.view_perspective != "CAMERA":
        return ""
    camera = region_camera(space, blender_scene)
    if camera is None:
        return ""
    if camera.type != "CAMERA":
        return "F12 renders Cycles' lens for an object that is not a camera; the viewport may show another"
    data = camera.data
    if data.type == "PANO":
        return "F12 renders the panorama; the viewport shows Blender's perspective view of it"
    if data.dof.use_dof:
        return "F12 renders the depth of field; the viewport does not"
    return ""
