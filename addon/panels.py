"""The sidebar tab View3D ▸ N ▸ BVH: build, stats, overlay, render, compare, export."""

from __future__ import annotations

import bpy

from bvhlab.build_config import BINNED_METHODS

from . import state
from .overlay import is_two_level, scene_batch
from .text_layout import wrapped_label


def draw_build_settings(col, settings) -> None:
    """The tree's settings, as the sidebar and the engine's BVH panel show them."""
    col.prop(settings, "method")
    binned = col.column()
    binned.enabled = settings.method in BINNED_METHODS  # sah and sbvh
    binned.prop(settings, "bins")
    binned.prop(settings, "bin_bounds")
    col.prop(settings, "axis")
    col.prop(settings, "max_leaf_size")
    col.prop(settings, "sah_block")  # the SAH methods' (Compare's SAH rows take it too)
    col.prop(settings, "update_policy")  # moved or edited meshes (the viewport, F12)


class _BvhPanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "BVH"


class BVHLAB_PT_main(_BvhPanel, bpy.types.Panel):
    bl_label = "BVH"

    def draw(self, context):
        layout = self.layout
        settings = context.scene.bvhlab
        if state.core_warning:
            wrapped_label(layout.box(), context, state.core_warning, icon="ERROR")
        col = layout.column(align=True)
        col.prop(settings, "scope", expand=True)
        col = layout.column()
        col.use_property_split = True
        draw_build_settings(col, settings)
        layout.operator("bvhlab.build", icon="MOD_LATTICE")
        built = state.tree_for(context.scene)
        if built is not None:
            _stats_box(layout, built, settings)
        message = state.messages.get(state.key(context.scene))
        if message is not None:
            icon = {"ERROR": "ERROR", "WARNING": "INFO"}.get(message[0], "CHECKMARK")
            wrapped_label(layout, context, message[1], icon=icon)


def milliseconds(ms: float) -> str:
    """A time for a table cell, in ms: whole from 10 ms on, two significant digits below (a
    sub-millisecond build is 0.35, not 0)."""
    if ms >= 10:
        return f"{ms:.0f}"
    return f"{ms:.2g}" if ms >= 0.01 else "<0.01"


def stats_rows(stats: dict) -> list[tuple[str, str]]:
    """(label, value) of each statistic the panel shows, in order (a two-level tree's: stored
    against flattened, its TLAS and BLASes)."""
    s = stats
    if "tlas_nodes" in s:
        return two_level_rows(s)
    return [
        ("Primitives", f"{s['primitives']:,}"),
        ("Nodes", f"{s['nodes']:,}"),
        ("Leaves", f"{s['leaves']:,}"),
        ("Height", str(s["height"])),
        ("SAH cost", f"{s['sah_cost']:.2f}"),
        ("Build", f"{milliseconds(s['build_ms'])} ms"),
        ("Memory", f"{s['memory_bytes'] / 2**20:.1f} MiB"),
        ("Method", s["method"]),
    ]


def two_level_rows(s: dict) -> list[tuple[str, str]]:
    """The rows of an instanced scene's two-level tree (InstancedBvh.stats)."""
    mib = 2**20
    return [
        ("Meshes", f"{s['meshes']:,}"),
        ("Instances", f"{s['instances']:,}"),
        ("Triangles stored", f"{s['triangles']:,}"),
        ("Triangles flattened", f"{s['triangles_flattened']:,}"),
        ("TLAS nodes", f"{s['tlas_nodes']:,}"),
        ("BLAS nodes", f"{s['nodes'] - s['tlas_nodes']:,}"),
        ("Height", f"{s['tlas_height']} + {max(s['mesh_height'], default=0)}"),
        ("SAH cost", f"{s['sah_cost']:.2f}"),
        ("TLAS SAH cost", f"{s['tlas_sah_cost']:.2f}"),
        ("Build", f"{milliseconds(s['build_ms'])} ms"),
        ("Memory", f"{s['memory_bytes'] / mib:.1f} MiB"),
        ("TLAS memory", f"{s['tlas_memory_bytes'] / mib:.2f} MiB"),
        ("Method", s["method"]),
    ]


def update_rows(tree) -> list[tuple[str, str]]:
    """The last update of the tree (trees.SceneTree.last): what ran, its policy, ms and SAH cost,
    and a fresh build's SAH cost once measured."""
    last = tree.last
    if last is None:
        return []
    what = last.action + (f" ({last.policy})" if last.policy else "")
    rows = [
        ("Last update", what),
        ("Update time", f"{milliseconds(last.ms)} ms"),
        ("SAH after", f"{last.sah_cost:.2f}"),
    ]
    fresh = tree.known_fresh_sah_cost()
    if fresh is not None:
        rows.append(("Fresh build SAH", f"{fresh:.2f}"))
    return rows


def _stats_box(layout, built, settings) -> None:
    """One row per statistic, label | value (a grid_flow would fill columns first)."""
    box = layout.box()
    col = box.column(align=True)
    for label, value in stats_rows(built.bvh.stats) + update_rows(built.tree):
        row = col.split(factor=0.5)
        row.label(text=label)
        row.label(text=value)
    if built.tree.known_fresh_sah_cost() is None:
        box.operator("bvhlab.fresh_sah", icon="TIME")
    if built.settings != settings.build_settings():
        box.label(text="Settings changed; build again", icon="INFO")
    if built.behind:
        box.label(text=BEHIND_NOTES[built.behind], icon="INFO")


#: What the panel says of a tree the scene may have left behind (state.BuiltTree.behind).
BEHIND_NOTES = {
    state.EDITED: "Scene edited since; show the boxes or build again",
    state.UNDONE: "Undo since; show the boxes or build again",
    state.RENDERED: "A render changed the tree; show the boxes or build again",
    state.NOT_FOLLOWED: "The boxes stopped following the scene; build again",
}


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
        two_level = built is not None and is_two_level(built)
        if two_level:  # an instanced scene: which level's boxes, and what the cap leaves out
            layout.prop(settings, "overlay_level", expand=True)
            note = scene_batch(context.scene, built).table.note if settings.overlay_show else ""
            if note:
                wrapped_label(layout, context, note, icon="INFO")
        layout.prop(settings, "overlay_leaves_only")
        layout.prop(settings, "overlay_color_by_depth")
        if settings.overlay_color_by_depth and settings.overlay_measure == "depth":
            from .legend_icons import depth_legend

            depth_legend(layout, settings.overlay_depth_min, settings.overlay_depth_max)
        row = layout.row()
        row.enabled = not settings.overlay_color_by_depth
        row.prop(settings, "overlay_color")
        layout.prop(settings, "overlay_measure")  # of the analysed tree's nodes (Inspect ▸ Analyse Tree)
        if settings.overlay_measure != "depth" and built is not None:
            from .overlay import shown_measure

            if shown_measure(built, settings.overlay_measure) == "depth":
                layout.operator("bvhlab.analyse_tree", icon="VIEWZOOM")
            elif legend := scene_batch(context.scene, built).table.legend:
                layout.label(text=legend.text())
        layout.prop(settings, "overlay_xray")
        layout.prop(settings, "overlay_line_width")


class BVHLAB_PT_inspect(_BvhPanel, bpy.types.Panel):
    bl_label = "Inspect"
    bl_parent_id = "BVHLAB_PT_main"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        from .ops_inspect import draw_inspect_panel

        draw_inspect_panel(self.layout, context.scene)


class BVHLAB_PT_cost(_BvhPanel, bpy.types.Panel):
    bl_label = "Cost per Depth"
    bl_parent_id = "BVHLAB_PT_inspect"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        from .ops_costs import draw_cost_panel

        draw_cost_panel(self.layout, context.scene)


class BVHLAB_PT_render(_BvhPanel, bpy.types.Panel):
    bl_label = "Render"
    bl_parent_id = "BVHLAB_PT_main"

    def draw(self, context):
        from .ops_render import render_size

        settings = context.scene.bvhlab
        layout = self.layout
        width, height = render_size(context.scene)
        layout.label(text=f"Output {width} × {height} px", icon="OUTPUT")
        col = layout.column()
        col.use_property_split = True
        for name in ("render_bounces", "render_supersampling", "backend", "traversal", "render_mode", "render_overlay"):
            col.prop(settings, name)
        layout.operator("bvhlab.render", icon="RENDER_STILL")
        timings = state.last_render.get(state.key(context.scene))
        if timings:
            box = layout.box()
            wrapped_label(box, context, f"{timings['device']} ({timings['backend']})", in_box=True)
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
            box = layout.box()
            for columns in COMPARE_TABLES:
                _compare_table(box.column(align=True), rows, columns)
            box.label(text="Frame and build in ms")


#: The Compare table, as two tables of method | two numbers: one row of method | four numbers
#: does not fit the sidebar's default width (its header showed "Hei...").
COMPARE_TABLES = (
    (("Frame", lambda r: milliseconds(r["frame_ms"])), ("Build", lambda r: milliseconds(r["build_ms"]))),
    (("Height", lambda r: str(r["height"])), ("SAH cost", lambda r: f"{r['sah_cost']:.1f}")),
)


def _compare_table(col, rows, columns) -> None:
    """A header and one row per method: method | the columns' values."""
    for texts in [("Method", *(name for name, _ in columns))] + [
        (r["method"], *(value(r) for _, value in columns)) for r in rows
    ]:
        row = col.split(factor=0.4)
        row.label(text=texts[0])
        numbers = row.row(align=True)
        for text in texts[1:]:
            numbers.label(text=text)


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
