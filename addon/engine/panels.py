"""Render Properties (and View Layer ▸ Passes) panels of the engine. Every setting is one of
scene.bvhlab's (the sidebar panel shows the same ones) or Blender's own."""

from __future__ import annotations

import bpy

from ..panels import draw_build_settings
from . import records
from .engine import ENGINE_ID
from .passes import HEATMAP_PROPERTY


class _EnginePanel:
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    COMPAT_ENGINES = {ENGINE_ID}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def _column(self):
        self.layout.use_property_split = True
        self.layout.use_property_decorate = False
        return self.layout.column()


class BVHLAB_PT_engine_bvh(_EnginePanel, bpy.types.Panel):
    bl_label = "BVH"

    def draw(self, context):
        settings = context.scene.bvhlab
        draw_build_settings(self._column(), settings)


class BVHLAB_PT_engine_tracing(_EnginePanel, bpy.types.Panel):
    bl_label = "Tracing"

    def draw(self, context):
        settings = context.scene.bvhlab
        col = self._column()
        col.prop(settings, "render_bounces", text="Ray Depth")
        col.prop(settings, "render_supersampling", text="Samples (n × n)")
        col.prop(settings, "traversal")
        col.prop(settings, "backend")


class BVHLAB_PT_engine_boxes(_EnginePanel, bpy.types.Panel):
    bl_label = "BVH Boxes"

    def draw(self, context):
        settings = context.scene.bvhlab
        col = self._column()
        col.prop(settings, "render_overlay", text="In Render")
        col.prop(settings, "overlay_show", text="In Viewport")
        sub = col.column(align=True)
        sub.active = settings.render_overlay or settings.overlay_show
        sub.prop(settings, "overlay_depth_min", text="Depth Min")
        sub.prop(settings, "overlay_depth_max", text="Max")
        sub = col.column()
        sub.active = settings.render_overlay or settings.overlay_show
        sub.prop(settings, "overlay_color_by_depth")
        sub.prop(settings, "overlay_line_width")


class BVHLAB_PT_engine_viewport(_EnginePanel, bpy.types.Panel):
    bl_label = "Viewport"

    def draw(self, context):
        settings = context.scene.bvhlab
        col = self._column()
        col.prop(settings, "render_mode", text="Display")
        col.prop(settings, "viewport_budget_ms")


class BVHLAB_PT_engine_performance(_EnginePanel, bpy.types.Panel):
    bl_label = "Performance"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        col = self._column()
        col.prop(context.scene.render, "use_persistent_data", text="Persistent Data")
        col.label(text="Keeps the scene and tree between frames")


class BVHLAB_PT_engine_status(_EnginePanel, bpy.types.Panel):
    bl_label = "Last Render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        key = records.key(context.scene)
        with records.lock:
            final, viewport = records.last_final.get(key), dict(records.last_viewport.get(key, {}))
        col = self.layout.column(align=True)
        if final is None and not viewport:
            col.label(text="Nothing rendered yet")
        if final is not None:
            size = f"{final['size'][0]} × {final['size'][1]}"
            col.label(text=f"{size}, {final['samples']} samples per pixel on {final['device']}")
            col.label(text=f"BVH {final['tree']} {final['build_ms']:.0f} ms, trace {final['trace_ms']:.0f} ms")
            if final.get("note"):
                col.label(text=final["note"], icon="INFO")
        for level, t in viewport.items():
            col.label(text=f"Viewport {level}: {t['width']} × {t['height']}, trace {t['trace_ms']:.0f} ms")


class BVHLAB_PT_engine_passes(_EnginePanel, bpy.types.Panel):
    bl_label = "Passes"
    bl_context = "view_layer"

    def draw(self, context):
        col = self._column()
        col.label(text="Combined is always rendered")
        col.prop(context.view_layer, "use_pass_z", text="Depth")
        col.prop(context.view_layer, HEATMAP_PROPERTY)


classes = (
    BVHLAB_PT_engine_bvh,
    BVHLAB_PT_engine_tracing,
    BVHLAB_PT_engine_boxes,
    BVHLAB_PT_engine_viewport,
    BVHLAB_PT_engine_performance,
    BVHLAB_PT_engine_status,
    BVHLAB_PT_engine_passes,
)
