"""The sidebar tab View3D ▸ N ▸ BVH: build, stats, overlay, render, compare, export."""
from __future__ import annotations

import bpy

from . import state


class _BvhPanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "BVH"


class BVHLAB_PT_main(_BvhPanel, bpy.types.Panel):
    bl_label = "BVH"

    def draw(self, context):
        layout = self.layout
        settings = context.scene.bvhlab
        col = layout.column(align=True)
        col.prop(settings, "scope", expand=True)
        col = layout.column()
        col.use_property_split = True
        col.prop(settings, "method")
        row = col.row()
        row.enabled = settings.method == "sah"
        row.prop(settings, "bins")
        col.prop(settings, "axis")
        col.prop(settings, "max_leaf_size")
        layout.operator("bvhlab.build", icon="MOD_LATTICE")
        built = state.tree_for(context.scene)
        if built is not None:
            _stats_box(layout, built, settings)
        message = state.messages.get(state.key(context.scene))
        if message is not None:
            icon = {"ERROR": "ERROR", "WARNING": "INFO"}.get(message[0], "CHECKMARK")
            layout.label(text=message[1], icon=icon)


def _stats_box(layout, built, settings) -> None:
    s = built.bvh.stats
    box = layout.box()
    grid = box.grid_flow(columns=2, even_columns=True)
    for label, value in (("Primitives", f"{s['primitives']:,}"), ("Nodes", f"{s['nodes']:,}"),
                         ("Leaves", f"{s['leaves']:,}"), ("Height", str(s["height"])),
                         ("SAH cost", f"{s['sah_cost']:.2f}"), ("Build", f"{s['build_ms']:.1f} ms"),
                         ("Memory", f"{s['memory_bytes'] / 2**20:.1f} MiB"), ("Method", s["method"])):
        grid.label(text=label)
        grid.label(text=value)
    if built.settings != settings.build_settings():
        box.label(text="Settings changed since this build", icon="INFO")


class BVHLAB_PT_overlay(_BvhPanel, bpy.types.Panel):
    bl_label = "Viewport Boxes"
    bl_parent_id = "BVHLAB_PT_main"

    def draw_header(self, context):
        self.layout.prop(context.scene.bvhlab, "overlay_show", text="")

    def draw(self, context):
        settings = context.scene.bvhlab
        layout = self.layout
        layout.use_property_split = True
        layout.active = settings.overlay_show
        built = state.tree_for(context.scene)
        col = layout.column(align=True)
        col.prop(settings, "overlay_depth_min", text="Depth min")
        col.prop(settings, "overlay_depth_max", text="Max")
        if built is None:
            layout.label(text="Build a tree to see its boxes", icon="INFO")
        else:
            layout.label(text=f"Depths 0 – {built.height - 1}")
        layout.prop(settings, "overlay_leaves_only")
        layout.prop(settings, "overlay_color_by_depth")
        row = layout.row()
        row.enabled = not settings.overlay_color_by_depth
        row.prop(settings, "overlay_color")
        layout.prop(settings, "overlay_xray")
        layout.prop(settings, "overlay_line_width")


class BVHLAB_PT_render(_BvhPanel, bpy.types.Panel):
    bl_label = "Render"
    bl_parent_id = "BVHLAB_PT_main"

    def draw(self, context):
        from .ops_render import render_size

        settings = context.scene.bvhlab
        layout = self.layout
        width, height = render_size(context.scene)
        layout.label(text=f"Resolution {width} × {height} (from the scene's output)")
        col = layout.column()
        col.use_property_split = True
        for name in ("render_bounces", "render_supersampling", "backend", "traversal", "render_mode", "render_overlay"):
            col.prop(settings, name)
        layout.operator("bvhlab.render", icon="RENDER_STILL")
        timings = state.last_render.get(state.key(context.scene))
        if timings:
            box = layout.box()
            box.label(text=f"{timings['device']} ({timings['backend']})")
            for name in ("upload_ms", "overlay_ms", "trace_ms", "readback_ms", "total_ms"):
                if name in timings:
                    box.label(text=f"{name[:-3].capitalize()}: {timings[name]:.1f} ms")


class BVHLAB_PT_compare(_BvhPanel, bpy.types.Panel):
    bl_label = "Compare Methods"
    bl_parent_id = "BVHLAB_PT_main"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        settings = context.scene.bvhlab
        layout = self.layout
        col = layout.column()
        col.use_property_split = True
        col.prop(settings, "compare_frames")
        col.prop(settings, "compare_filepath")
        layout.operator("bvhlab.compare", icon="SORTTIME")
        rows = state.comparisons.get(state.key(context.scene))
        if rows:
            grid = layout.box().grid_flow(columns=5, row_major=True, even_columns=False)
            for header in ("Method", "Frame ms", "Build ms", "Height", "SAH"):
                grid.label(text=header)
            for r in rows:
                for text in (r["label"], f"{r['frame_ms']:.1f}", f"{r['build_ms']:.1f}", str(r["height"]),
                             f"{r['sah_cost']:.2f}"):
                    grid.label(text=text)


class BVHLAB_PT_export(_BvhPanel, bpy.types.Panel):
    bl_label = "Export"
    bl_parent_id = "BVHLAB_PT_main"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        self.layout.operator("bvhlab.export_stats", icon="EXPORT")


class BVHLAB_PT_object(_BvhPanel, bpy.types.Panel):
    bl_label = "Active Object"
    bl_parent_id = "BVHLAB_PT_main"

    @classmethod
    def poll(cls, context):
        return context.object is not None and context.object.type == "MESH"

    def draw(self, context):
        self.layout.prop(context.object, "bvhlab_analytic_sphere")
