"""The render engine "bvhlab Whitted" (Render Properties ▸ Render Engine): F12 and the command line
render into Blender's Render Result (Combined, Depth, BVH Heatmap passes), and the 3D viewport's
Rendered shading traces the current view live with the BVH boxes (report §3.3).

engine.py routes Blender's calls; final.py (final renders) and viewport.py (a worker thread per
viewport) do the work through tracer.py, the one module that calls bvhlab's tracer."""

from __future__ import annotations

import bpy

from . import panels
from .blender_panels import engine_panels
from .engine import ENGINE_ID, BVHLAB_RE_whitted
from .light_distance import BVHLAB_OT_measure_light_distance
from .operators import BVHLAB_OT_viewport_cancel

classes = (BVHLAB_RE_whitted, BVHLAB_OT_viewport_cancel, BVHLAB_OT_measure_light_distance, *panels.classes)
_keymaps: list = []


def register() -> None:
    from .final import forget_job_light

    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.app.handlers.render_init.append(forget_job_light)  # a render job's frames share a light
    for panel in engine_panels():
        panel.COMPAT_ENGINES.add(ENGINE_ID)
    _add_keymap()


def unregister() -> None:
    from .display import forget_shader
    from .final import forget_job_light
    from .tracer import forget_tracers
    from .viewport import close_all

    if forget_job_light in bpy.app.handlers.render_init:
        bpy.app.handlers.render_init.remove(forget_job_light)
    _remove_keymap()
    close_all()
    forget_shader()
    for panel in engine_panels():
        panel.COMPAT_ENGINES.discard(ENGINE_ID)
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
    forget_tracers()  # what the engine remembers is in the add-on's state (cleared by the add-on)


def forget() -> None:
    """Another file is loading: its scenes are not these (the add-on clears its state beside)."""
    from .viewport import close_all

    close_all()


def _add_keymap() -> None:
    """Esc in the 3D viewport cancels a Rendered viewport's build (only while one runs: otherwise
    the operator's poll fails and Esc goes on to Blender's own handlers)."""
    config = bpy.context.window_manager.keyconfigs.addon
    if config is None:  # background mode
        return
    keymap = config.keymaps.new(name="3D View", space_type="VIEW_3D")
    _keymaps.append((keymap, keymap.keymap_items.new(BVHLAB_OT_viewport_cancel.bl_idname, "ESC", "PRESS")))


def _remove_keymap() -> None:
    for keymap, item in _keymaps:
        keymap.keymap_items.remove(item)
    _keymaps.clear()
