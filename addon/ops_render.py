"""Render (`bvhlab.render`): trace the scene with the Whitted tracer into the Image "BVH Render"."""

from __future__ import annotations

import bpy

from . import state
from .image_output import IMAGE_NAME, show_render
from .operator_support import current_tree, export_scene, run_reported


def render_size(scene) -> tuple[int, int]:
    """The scene's output resolution (percentage applied)."""
    render = scene.render
    scale = render.resolution_percentage / 100
    return max(1, round(render.resolution_x * scale)), max(1, round(render.resolution_y * scale))


def render_with_settings(context, exported, bvh):
    """One frame with the panel's render settings; returns (image, timings)."""
    import bvhlab

    settings = context.scene.bvhlab
    width, height = render_size(context.scene)
    overlay = (settings.overlay_depth_min, settings.overlay_depth_max) if settings.render_overlay else None
    return bvhlab.render(
        exported,
        bvh,
        width,
        height,
        backend=settings.backend,
        samples_per_axis=settings.render_supersampling,
        max_depth=settings.render_bounces,
        overlay_depth=overlay,
        traversal=settings.traversal,
        mode=settings.render_mode,
        color_by_depth=settings.overlay_color_by_depth,
        line_width=settings.overlay_line_width,
    )


class BVHLAB_OT_render(bpy.types.Operator):
    """Ray trace the scene with bvhlab's Whitted tracer into the Image "BVH Render\""""

    bl_idname = "bvhlab.render"
    bl_label = "Render"
    bl_options = {"REGISTER"}

    def execute(self, context):
        return run_reported(self, context, lambda: self._render(context))

    def _render(self, context):
        exported = export_scene(context, require_camera=True)
        built = current_tree(context, exported)
        pixels, timings = render_with_settings(context, exported, built.bvh)
        where = show_in_image_editor(context, show_render(context, pixels))
        state.last_render[state.key(context.scene)] = dict(timings)
        fallback = f" (fell back: {timings['fallback']})" if timings.get("fallback") else ""
        message = (
            f"Image '{IMAGE_NAME}' ({where}): {pixels.shape[1]}×{pixels.shape[0]} on {timings['device']} "
            f"[{timings['backend']}]{fallback}: trace {timings['trace_ms']:.1f} ms, "
            f"total {timings['total_ms']:.1f} ms"
        )
        self.report({"INFO"}, message)
        state.messages[state.key(context.scene)] = ("INFO", message)
        return {"FINISHED"}


def _image_editors(context, image=None) -> list:
    """The Image Editor areas of every window (those showing `image`, when given)."""
    return [
        area
        for window in context.window_manager.windows
        for area in window.screen.areas
        if area.type == "IMAGE_EDITOR" and (image is None or area.spaces.active.image == image)
    ]


def show_in_image_editor(context, image) -> str:
    """Show the image as F12 shows its result: in the Image Editors showing it already, else where
    Preferences ▸ Interface ▸ Render In says (a new window by default: the default Layout has no
    Image Editor). Returns where it is, for the report."""
    if _image_editors(context, image):
        return "in the Image Editor"
    if context.window is None or context.preferences.view.render_display_type == "NONE":
        return "open it in an Image Editor"
    before = {area.as_pointer() for area in _image_editors(context)}
    bpy.ops.render.view_show("INVOKE_DEFAULT")  # Blender's render view: opens the editor F12 would
    editors = _image_editors(context)
    # a new one; or, where the render window was open already (Blender raises it), that window's
    opened = [area for area in editors if area.as_pointer() not in before] or [
        area for area in editors if area.id_data.is_temporary
    ]
    for area in opened:
        area.spaces.active.image = image
    return "shown in a new Image Editor" if opened else "open it in an Image Editor"
