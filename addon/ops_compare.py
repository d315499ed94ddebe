"""Compare methods (`bvhlab.compare`): the report's Table 1 for the open scene — every split method
built and rendered with bvhlab.compare's protocol (the same as `bvhlab compare` on the command
line), with frame time, build time, tree height and SAH cost."""
from __future__ import annotations

import bpy

from . import state
from .operator_support import export_scene, output_path, run_reported
from .ops_render import render_size

#: (label, method label of bvhlab.compare): every split method, SAH at the report's 12 and 32 bins.
COMPARE_METHODS = (
    ("Median", "median"), ("Mean", "mean"), ("Midpoint", "midpoint"), ("SAH 12 bins", "sah12"),
    ("SAH 32 bins", "sah32"), ("SAH full sweep", "sweep_sah"), ("LBVH", "lbvh"),
)


class BVHLAB_OT_compare(bpy.types.Operator):
    """Build and render the scene with every split method; show the table (frame time, build time,
    height, SAH cost) in the panel and write it as CSV"""
    bl_idname = "bvhlab.compare"
    bl_label = "Compare Methods"
    bl_options = {"REGISTER"}

    def execute(self, context):
        return run_reported(self, context, lambda: self._compare(context))

    def _compare(self, context):
        from bvhlab.compare import measure_methods, write_csv
        from bvhlab.render import default_renderer

        settings = context.scene.bvhlab
        exported = export_scene(context, require_camera=True)
        width, height = render_size(context.scene)
        labels = {method: label for label, method in COMPARE_METHODS}
        window_manager = context.window_manager
        started = []

        def progress(text: str) -> None:  # "<method>: building" starts each method
            if text.endswith("building"):
                started.append(text)
                window_manager.progress_update(len(started))

        window_manager.progress_begin(0, len(labels))
        try:
            rows = measure_methods(
                exported, list(labels), frames=settings.compare_frames, builds=1, width=width, height=height,
                renderer=default_renderer(settings.backend), samples_per_axis=settings.render_supersampling,
                max_depth=settings.render_bounces, progress=progress,
                build_options={"axis": settings.axis, "max_leaf_size": settings.max_leaf_size})
        finally:
            window_manager.progress_end()
        for row in rows:
            row["label"] = labels[row["method"]]
        state.comparisons[state.key(context.scene)] = rows
        path = write_csv(rows, output_path(settings.compare_filepath, "bvh_compare.csv"))
        best = min(rows, key=lambda row: row["frame_ms"])
        message = (f"Compared {len(rows)} methods; fastest frame: {best['label']} ({best['frame_ms']:.1f} ms); "
                   f"wrote {path}")
        self.report({"INFO"}, message)
        state.messages[state.key(context.scene)] = ("INFO", message)
        return {"FINISHED"}
