"""Render (`bvhlab.render`): trace the scene with the Whitted tracer into the Image "BVH Render"."""

from __future__ import annotations

import bpy

from . import state
from .engine.settings import final_threads
from .image_output import IMAGE_NAME, show_render
from .operator_support import current_tree, export_scene, run_reported


def render_size(scene) -> tuple[int, int]:
    """The scene's output resolution with the percentage applied as Blender applies it (integer
    division, BKE_render_resolution): the size F12 renders."""
    render = scene.render
    percent = render.resolution_percentage
    return max(1, render.resolution_x * percent // 100), max(1, render.resolution_y * percent // 100)


def render_with_settings(context, exported, bvh):
    """One frame with the scene's render options (the ones F12 uses); returns (image, timings)."""
    import bvhlab

    width, height = render_size(context.scene)
    settings = context.scene.bvhlab
    options = settings.render_options()
    threads = final_threads(context.scene)  # as F12: Render Properties ▸ Performance ▸ Threads
    return bvhlab.render(exported, bvh, width, height, backend=settings.backend, options=options, threads=threads)


class BVHLAB_OT_render(bpy.types.Operator):
    """Ray trace the scene with bvhlab's Whitted tracer into the Image "BVH Render\""""

    bl_idname = "bvhlab.render"
    bl_label = "Render"
    bl_options = {"REGISTER"}

    def execute(self, context):
        return run_reported(self, context, lambda: self._render(context))

    def _render(self, context):
        from bvhlab import legend

        exported = export_scene(context, require_camera=True)
        bvh = current_tree(context, exported)
        pixels, timings = render_with_settings(context, exported, bvh)
        # the legends of its colourings under it: the heatmap's scale, the boxes' depth colours
        options = context.scene.bvhlab.render_options()
        pixels = legend.render_legends(pixels, options, timings["heatmap_scale"], legend.overlay_height(bvh))
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
    # background: no window to open (a file loaded there has windows, whose operators Blender refuses)
    if bpy.app.background or context.window is None or context.preferences.view.render_display_type == "NONE":
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
