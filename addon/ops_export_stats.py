"""Export stats (`bvhlab.export_stats`): the tree's statistics as JSON and CSV."""
from __future__ import annotations

import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ExportHelper

from . import state
from .operator_support import build_tree, export_scene, output_path, remember_tree, run_reported
from .stats_files import write_stats_csv, write_stats_json


class BVHLAB_OT_export_stats(bpy.types.Operator, ExportHelper):
    """Write the BVH statistics (per-depth node counts, leaf-size histogram...) as JSON and CSV
    (the CSV beside the JSON, same name). Builds a tree first if the scene has none"""
    bl_idname = "bvhlab.export_stats"
    bl_label = "Export BVH Stats"
    bl_options = {"REGISTER"}

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    def execute(self, context):
        from bvhlab.blender import SubstituteWarning  # statistics need no camera or light

        return run_reported(self, context, lambda: self._export(context), quiet=(SubstituteWarning,))

    def _export(self, context):
        built = state.tree_for(context.scene)
        if built is None:
            exported = export_scene(context, require_camera=False)
            built = remember_tree(context, build_tree(context, exported), exported)
        json_path = output_path(self.filepath, "bvh_stats.json").with_suffix(".json")
        csv_path = json_path.with_suffix(".csv")
        stats = built.bvh.stats
        about = {"scene": context.scene.name, "blend_file": bpy.data.filepath, "settings": built.settings}
        write_stats_json(json_path, stats, about)
        write_stats_csv(csv_path, stats)
        message = f"Wrote {json_path} and {csv_path.name}"
        self.report({"INFO"}, message)
        state.messages[state.key(context.scene)] = ("INFO", message)
        return {"FINISHED"}
