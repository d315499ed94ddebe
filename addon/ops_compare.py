"""Compare methods (`bvhlab.compare`): the report's Table 1 for the open scene: every split method
built and rendered, with frame time, build time, tree height and SAH cost."""
from __future__ import annotations

import statistics

import bpy

from . import state
from .operator_support import build_tree, export_scene, output_path, run_reported
from .ops_render import render_with_settings
from .stats_files import write_compare_csv

#: (label, method, bins): every split method, SAH at the report's 12 and 32 bins.
COMPARE_CONFIGS = (
    ("Median", "median", 12), ("Mean", "mean", 12), ("Midpoint", "midpoint", 12),
    ("SAH 12 bins", "sah", 12), ("SAH 32 bins", "sah", 32), ("SAH full sweep", "sweep_sah", 12),
    ("LBVH", "lbvh", 12),
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
        settings = context.scene.bvhlab
        exported = export_scene(context, require_camera=True)
        rows = [self._measure(context, exported, *config) for config in COMPARE_CONFIGS]
        state.comparisons[state.key(context.scene)] = rows
        path = output_path(settings.compare_filepath, "bvh_compare.csv")
        write_compare_csv(path, rows)
        best = min(rows, key=lambda row: row["frame_ms"])
        message = (f"Compared {len(rows)} methods; fastest frame: {best['label']} ({best['frame_ms']:.1f} ms); "
                   f"wrote {path}")
        self.report({"INFO"}, message)
        state.messages[state.key(context.scene)] = ("INFO", message)
        return {"FINISHED"}

    @staticmethod
    def _measure(context, exported, label: str, method: str, bins: int) -> dict:
        """Build once, render `compare_frames` times. The frame time is the mean of overlay + trace
        time per frame (the per-frame work of the report's real-time loop, without the one-off
        upload and the readback)."""
        bvh = build_tree(context, exported, method=method, bins=bins)
        frames = [render_with_settings(context, exported, bvh)[1] for _ in range(context.scene.bvhlab.compare_frames)]
        s = bvh.stats
        return {"label": label, "method": method, "bins": bins, "build_ms": s["build_ms"], "height": s["height"],
                "sah_cost": s["sah_cost"], "nodes": s["nodes"],
                "frame_ms": statistics.fmean(t.get("overlay_ms", 0.0) + t["trace_ms"] for t in frames),
                "total_ms": statistics.fmean(t["total_ms"] for t in frames),
                "backend": frames[-1]["backend"], "device": frames[-1]["device"]}
