"""Render Properties (and View Layer ▸ Passes) panels of the engine. Every setting is one of
scene.bvhlab's (the sidebar panel shows the same ones) or Blender's own."""

from __future__ import annotations

import bpy

from .. import state
from ..legend_icons import heat_legend
from ..panels import draw_build_settings, milliseconds
from ..text_layout import wrapped_label
from .counter_view import NO_COUNTER
from .engine import ENGINE_ID
from .passes import COUNTERS_PROPERTY, HEATMAP_PROPERTY


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
        col.prop(settings, "render_supersampling", text="Samples")  # n × n: its tooltip says so
        col.prop(settings, "traversal")
        col.prop(settings, "backend")
        col.prop(settings, "light_distance", text="Light")  # its distance; 0: measured (the tooltip says so)
        col.operator("bvhlab.measure_light_distance", text="Measure Light Distance", icon="EYEDROPPER")


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
        col.prop(settings, "viewport_counter")
        if settings.viewport_counter != NO_COUNTER:
            col.prop(settings, "counter_range_auto")
            sub = col.column(align=True)
            sub.active = not settings.counter_range_auto
            sub.prop(settings, "counter_range_min")
            sub.prop(settings, "counter_range_max")
            _counter_legend(self.layout, context, settings)
            _counter_histogram(self.layout, context)
        col.prop(settings, "viewport_budget_ms")


def _counter_legend(layout, context, settings) -> None:
    """The heat ramp's colours with the numbers of the range the last viewport frame used."""
    from bvhlab.counters import AUTO_PERCENTILE, LABELS

    with state.lock:
        frames = dict(state.last_viewport.get(state.key(context.scene), {}))
    shown = [t for t in frames.values() if t.get("counter") == settings.viewport_counter and t.get("counter_range")]
    if not shown:
        layout.label(text="The legend follows the next viewport frame", icon="INFO")
        return
    lo, hi = shown[-1]["counter_range"]
    how = f"Auto: 0 to the {AUTO_PERCENTILE:g}th pct" if settings.counter_range_auto else "Manual range"
    heat_legend(layout, lo, hi, f"{LABELS[settings.viewport_counter]} per ray", how)


def _counter_histogram(layout, context) -> None:
    """The histogram of the Rendered viewport's latest counter frame, as the sidebar's Traversal
    Counters panel draws it (one definition: ops_counters.draw_histogram)."""
    from ..ops_counters import draw_histogram, shown_histograms

    for source, hist in shown_histograms(context.scene):
        if source == "Viewport":
            draw_histogram(layout.box(), source, hist)


class BVHLAB_PT_engine_performance(_EnginePanel, bpy.types.Panel):
    bl_label = "Performance"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        col = self._column()
        col.prop(context.scene.render, "use_persistent_data", text="Persistent Data")
        wrapped_label(self.layout, context, "Keeps the scene and tree between frames")


class BVHLAB_PT_engine_status(_EnginePanel, bpy.types.Panel):
    bl_label = "Last Render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        _watch_records()
        key = state.key(context.scene)
        with state.lock:
            final, viewport = state.last_final.get(key), dict(state.last_viewport.get(key, {}))
        layout = self.layout
        if final is None and not viewport:
            layout.label(text="Nothing rendered yet")
        if final is not None:
            _rows(layout, context, final_rows(final))
            if final.get("note"):
                wrapped_label(layout, context, final["note"], icon="INFO")
            if final.get("overlay_note"):  # the BLAS boxes hit the cap (issue 34), as the sidebar says
                wrapped_label(layout, context, f"Overlay: {final['overlay_note']}", icon="INFO")
        if viewport:
            layout.label(text="Viewport")
            _rows(layout, context, [(level.capitalize(), _viewport_value(t)) for level, t in viewport.items()])


def final_rows(final: dict) -> list[tuple[str, str]]:
    """(label, value) rows of the last final render, as Last Render shows them."""
    tree = final["tree"] + ("" if final["tree"] == "kept" else f", {milliseconds(final['build_ms'])} ms")
    return [
        ("Size", f"{final['size'][0]} × {final['size'][1]}"),
        ("Samples", f"{final['samples']} per pixel"),
        ("Device", final["device"]),
        ("BVH", tree),
        ("Trace", f"{milliseconds(final['trace_ms'])} ms"),
    ]


def _viewport_value(t: dict) -> str:
    return f"{t['width']} × {t['height']}, {milliseconds(t['trace_ms'])} ms"


def _rows(layout, context, rows) -> None:
    """label | value rows; a value too long for its column wraps."""
    col = layout.column(align=True)
    for label, value in rows:
        row = col.split(factor=0.4)
        row.label(text=label)
        wrapped_label(row, context, value, share=0.6)


#: How often (s) Last Render looks for a finished render or a new viewport frame.
RECORDS_POLL_S = 0.25


def _watch_records() -> None:
    """The Properties editor redraws itself on a finished render only when the mouse moves over
    it: a UI-thread timer (started by the first draw of Last Render, stopped when the add-on is
    disabled) redraws it whenever what Last Render shows has changed."""
    if not bpy.app.timers.is_registered(_redraw_on_new_records):
        _shown[0] = _records_shown()
        bpy.app.timers.register(_redraw_on_new_records, first_interval=RECORDS_POLL_S, persistent=True)


_shown = [""]  # what Last Render showed when the timer last looked


def _records_shown() -> str:
    with state.lock:
        return repr((state.last_final, state.last_viewport))


def _redraw_on_new_records():
    if not BVHLAB_PT_engine_status.is_registered:
        return None
    shown = _records_shown()
    if shown != _shown[0]:
        _shown[0] = shown
        window_manager = bpy.context.window_manager
        for window in window_manager.windows if window_manager else ():
            for area in window.screen.areas:
                if area.type == "PROPERTIES":
                    area.tag_redraw()
    return RECORDS_POLL_S


class BVHLAB_PT_engine_passes(_EnginePanel, bpy.types.Panel):
    bl_label = "Passes"
    bl_context = "view_layer"

    def draw(self, context):
        col = self._column()
        col.label(text="Combined is always rendered")
        col.prop(context.view_layer, "use_pass_z", text="Depth")
        col.prop(context.view_layer, HEATMAP_PROPERTY)
        col.prop(context.view_layer, COUNTERS_PROPERTY)


classes = (
    BVHLAB_PT_engine_bvh,
    BVHLAB_PT_engine_tracing,
    BVHLAB_PT_engine_boxes,
    BVHLAB_PT_engine_viewport,
    BVHLAB_PT_engine_performance,
    BVHLAB_PT_engine_status,
    BVHLAB_PT_engine_passes,
)
