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
    )
