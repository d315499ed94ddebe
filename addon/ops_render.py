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
        show_render(context, pixels)
        state.last_render[state.key(context.scene)] = dict(timings)
        fallback = f" (fell back: {timings['fallback']})" if timings.get("fallback") else ""
        message = (
            f"{IMAGE_NAME}: {pixels.shape[1]}×{pixels.shape[0]} on {timings['device']} "
            f"[{timings['backend']}]{fallback}: trace {timings['trace_ms']:.1f} ms, "
            f"total {timings['total_ms']:.1f} ms"
        )
        self.report({"INFO"}, message)
        state.messages[state.key(context.scene)] = ("INFO", message)
        return {"FINISHED"}
