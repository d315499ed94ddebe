"""The engine's settings, read from the scene's one PropertyGroup (scene.bvhlab) that the sidebar
panel also uses: one definition of each setting."""

from __future__ import annotations

import os

from .tracer import TraceSettings

#: The viewport leaves one core to Blender's UI thread (orbiting stays fluid while a frame traces
#: or the tree builds).
VIEWPORT_THREADS = max(1, (os.cpu_count() or 2) - 1)


def trace_settings(blender_scene, *, viewport: bool, refined: bool = True) -> TraceSettings:
    """What a render of this scene uses. Final renders: shaded, n×n samples, the boxes when "Boxes
    in image" is on. The viewport: its mode (shade or heatmap), the boxes when "Show boxes" is on,
    n×n samples only once `refined`, one core fewer than the machine has."""
    s = blender_scene.bvhlab
    show_boxes = s.overlay_show if viewport else s.render_overlay
    return TraceSettings(
        samples_per_axis=s.render_supersampling if refined else 1,
        max_depth=s.render_bounces,
        overlay=(s.overlay_depth_min, s.overlay_depth_max) if show_boxes else None,
        color_by_depth=s.overlay_color_by_depth,
        line_width=s.overlay_line_width,
        traversal=s.traversal,
        mode=s.render_mode if viewport else "shade",
        threads=VIEWPORT_THREADS if viewport else 0,
    )


def backend(blender_scene) -> str:
    return blender_scene.bvhlab.backend
