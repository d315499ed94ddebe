"""Traversal counters in the sidebar (issue 35): the counter view's settings (the same the Rendered
viewport shows: counter, auto or manual range), Render Counter (`bvhlab.render_counter`: the
counter of every pixel on the heat ramp with its scale bar, in the Image "BVH Render") with the
histogram of what was shown (that render, and the Rendered viewport's latest frame) as rows,
and Compare Two Trees (`bvhlab.counter_diff`): the counter of the same view with the trees of two
Compare methods side by side over the counter view's range (the Image "BVH Two Trees") and their
per-pixel difference with its legend (the Image "BVH Counter Difference"), by the code of
`bvhlab compare --counter-diff` (bvhlab.compare.counter_diff)."""

from __future__ import annotations

import bpy

from . import state
from .engine.counter_view import NO_COUNTER, counter_histogram, counter_view, manual_range, shown_range
from .image_output import show_render
from .operator_support import current_tree, export_scene, run_reported
from .ops_render import render_size
from .panels import _BvhPanel

#: The Images Compare Two Trees writes: the difference, and both trees' counters side by side.
DIFFERENCE_IMAGE = "BVH Counter Difference"
SIDE_BY_SIDE_IMAGE = "BVH Two Trees"


def _counter_chosen(context) -> bool:
    return context.scene.bvhlab.viewport_counter != NO_COUNTER


def _report(operator, context, message: str) -> set[str]:
    operator.report({"INFO"}, message)
    state.messages[state.key(context.scene)] = ("INFO", message)
    return {"FINISHED"}


class BVHLAB_OT_render_counter(bpy.types.Operator):
    """Trace the scene's primary rays counting the chosen traversal counter: the Image "BVH Render"
    shows it on the heat ramp with its scale bar, the panel its histogram"""

    bl_idname = "bvhlab.render_counter"
    bl_label = "Render Counter"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return _counter_chosen(context)

    def execute(self, context):
        return run_reported(self, context, lambda: self._render(context))

    def _render(self, context):
        from bvhlab import counters
        from bvhlab.render import default_renderer

        settings = context.scene.bvhlab
        view = counter_view(settings)
        assert view is not None  # poll
        exported = export_scene(context, require_camera=True)
        width, height = render_size(context.scene)
        options = settings.render_options().replace(traversal_counters=True)
        job = default_renderer(settings.backend).start(
            exported, current_tree(context, exported), width, height, options=options
        )
        job.run()
        kept = job.result(color=False, depth=False, cost=False, counters=True).counters
        values = counters.counter_plane(kept, view.counter)
        image, (lo, hi) = counters.counter_image(values, shown_range(values, view))
        show_render(context, image)
        hist = counter_histogram(kept, view)
        state.counter_results.setdefault(state.key(context.scene), {})["histogram"] = hist
        p = hist.percentiles
        return _report(
            self,
            context,
            f"{counters.LABELS[view.counter]} per primary ray on {width}×{height}: mean {hist.mean:.2f}, "
            f"p99 {p['p99']:g}, max {p['max']:g}; colours {lo:g}..{hi:g}",
        )


class BVHLAB_OT_counter_diff(bpy.types.Operator):
    """Render the chosen traversal counter with the trees of two methods (built as Compare Methods
    builds them) and show their per-pixel difference, first minus second, red where the first
    costs more, with its legend (the same as `bvhlab compare --counter-diff`)"""

    bl_idname = "bvhlab.counter_diff"
    bl_label = "Compare Two Trees"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return _counter_chosen(context)

    def execute(self, context):
        return run_reported(self, context, lambda: self._compare(context))

    def _compare(self, context):
        from bvhlab.compare import counter_diff
        from bvhlab.render import default_renderer

        from .ops_compare import compare_build_options

        settings = context.scene.bvhlab
        first, second = settings.counter_diff_first, settings.counter_diff_second
        if first == second:
            raise ValueError(f"choose two different methods to compare (both are {first})")
        # As `bvhlab compare`: the split methods over the geometry as it stands (one level).
        exported = export_scene(context, require_camera=True).flattened()
        trees = counter_diff.build_trees(exported, (first, second), compare_build_options(settings))
        width, height = render_size(context.scene)
        view = counter_view(settings)
        assert view is not None  # poll
        result = counter_diff.counter_difference(
            exported,
            *trees,
            view.counter,
            width,
            height,
            renderer=default_renderer(settings.backend),
            labels=(first, second),
            options=settings.render_options(),
            value_range=manual_range(view),  # the side-by-side's colours: the counter view's range
        )
        show_render(context, result["side_by_side"], SIDE_BY_SIDE_IMAGE)
        show_render(context, result["image"], DIFFERENCE_IMAGE)
        state.counter_results.setdefault(state.key(context.scene), {})["difference"] = result["summary"]
        s = result["summary"]
        return _report(
            self,
            context,
            f"Images '{SIDE_BY_SIDE_IMAGE}', '{DIFFERENCE_IMAGE}': {first} − {second}, "
            f"mean {s['first_minus_second']['mean']:+.2f} per primary ray; {first} costs more on "
            f"{s['pixels_first_more']:,} pixels, less on {s['pixels_first_less']:,}",
        )


def shown_histograms(scene) -> list[tuple[str, object]]:
    """(where from, CounterHistogram) of each counter shown: the Rendered viewport's latest frame
    that showed one (its final level when there is one), the sidebar's last Render Counter."""
    with state.lock:
        frames = dict(state.last_viewport.get(state.key(scene), {}))
    shown = [("Viewport", t["counter_histogram"]) for t in frames.values() if t.get("counter_histogram") is not None]
    own = state.counter_results.get(state.key(scene), {}).get("histogram")
    return shown[-1:] + ([("Render", own)] if own is not None else [])


def draw_histogram(layout, source: str, hist) -> None:
    """One row per bin: its values with the swatch of its colour, a bar as long as its share of the
    tallest bin, its pixel count; then the percentiles."""
    from bvhlab.counters import LABELS

    from .legend_icons import swatch_icon

    col = layout.column(align=True)
    col.label(text=LABELS[hist.counter])
    col.label(text=f"{source}, {'auto' if hist.auto else 'manual'} range")
    tallest = max(int(hist.counts.max(initial=0)), 1)
    for text, count, rgb in zip(hist.bin_labels(), hist.counts, hist.colors()):
        row = col.split(factor=0.35, align=True)
        row.label(text=text, icon_value=swatch_icon(rgb))
        row.progress(factor=int(count) / tallest, type="BAR", text=f"{int(count):,}")
    p = hist.percentiles
    col.label(text=f"p50 {p['p50']:g} · p90 {p['p90']:g}")
    col.label(text=f"p99 {p['p99']:g} · max {p['max']:g}")


def _draw_difference(layout, summary: dict) -> None:
    from .legend_icons import diverging_legend

    col = layout.column(align=True)
    first, second = summary["first"], summary["second"]
    for label, key in ((first, first), (second, second), (f"{first} − {second}", "first_minus_second")):
        row = col.split(factor=0.5)
        row.label(text=label)
        row.label(text=f"mean {summary[key]['mean']:.2f}")
    col.label(text=f"{first} more: {summary['pixels_first_more']:,} px, less: {summary['pixels_first_less']:,} px")
    diverging_legend(layout, summary["span"], f"{first} − {second}", f"Auto: ± {summary['auto_percentile']:g}th pct")


class BVHLAB_PT_counters(_BvhPanel, bpy.types.Panel):
    bl_label = "Traversal Counters"
    bl_parent_id = "BVHLAB_PT_main"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        settings = context.scene.bvhlab
        layout = self.layout
        col = layout.column()
        col.use_property_split = True
        col.prop(settings, "viewport_counter")
        col.prop(settings, "counter_range_auto")
        sub = col.column(align=True)
        sub.active = not settings.counter_range_auto
        sub.prop(settings, "counter_range_min")
        sub.prop(settings, "counter_range_max")
        layout.operator("bvhlab.render_counter", icon="RENDER_STILL")
        for source, hist in shown_histograms(context.scene):
            draw_histogram(layout.box(), source, hist)
        box = layout.box()
        box.label(text="Two trees, the same view")
        col = box.column()
        col.use_property_split = True
        col.prop(settings, "counter_diff_first")
        col.prop(settings, "counter_diff_second")
        box.operator("bvhlab.counter_diff", icon="SPLIT_HORIZONTAL")
        summary = state.counter_results.get(state.key(context.scene), {}).get("difference")
        if summary is not None:
            _draw_difference(box, summary)


classes = (BVHLAB_OT_render_counter, BVHLAB_OT_counter_diff, BVHLAB_PT_counters)
