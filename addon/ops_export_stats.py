"""Export stats (`bvhlab.export_stats`): the tree's statistics as JSON and CSV."""

from __future__ import annotations

import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ExportHelper

from . import state
from .operator_support import current_tree, export_scene, named_output_path, run_reported, temporary_note
from .properties import output_path_options


class BVHLAB_OT_export_stats(bpy.types.Operator, ExportHelper):
    """Write the BVH statistics (per-depth node counts, leaf-size histogram...) as JSON and CSV
    (the CSV beside the JSON, same name). Builds a tree first if the scene has none, or brings it
    up to date when the scene may have changed since"""

    bl_idname = "bvhlab.export_stats"
    bl_label = "Export BVH Stats"
    bl_options = {"REGISTER"}

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})
    # ExportHelper's, with the options of a path the add-on writes ("//" included)
    filepath: StringProperty(
        name="File Path",
        description="The JSON file; the CSV is written beside it",
        subtype="FILE_PATH",
        options=output_path_options(),
    )

    def execute(self, context):
        from bvhlab.blender import SubstituteWarning  # statistics need no camera or light

        return run_reported(self, context, lambda: self._export(context), quiet=(SubstituteWarning,))

    def _export(self, context):
        from bvhlab.stats_files import write_stats

        from . import follow

        json_path = stats_json_path(self.filepath)  # refused before any work
        follow.settle(state.key(context.scene))  # an update the follow is making: its stats
        built = state.tree_for(context.scene)
        if built is None or built.behind:  # the stats of the scene as it is (kept if the tree fits)
            current_tree(context, export_scene(context, require_camera=False))
            built = state.tree_for(context.scene)
        csv_path = json_path.with_suffix(".csv")
        stats = built.bvh.stats
        about = {"scene": context.scene.name, "blend_file": bpy.data.filepath, "settings": built.settings}
        write_stats(stats, about, json_path, csv_path)
        message = f"Wrote {json_path} and {csv_path.name}" + temporary_note(json_path)
        self.report({"INFO"}, message)
        state.messages[state.key(context.scene)] = ("INFO", message)
        return {"FINISHED"}


def stats_json_path(filepath: str):
    """Where the JSON goes: the path as given, or with .json added when it has no suffix (the file
    browser's convention); a folder or another suffix is refused, never rewritten (issue 8.10)."""
    from bvhlab.stats_files import json_path

    # (".json" alone is a stem-less name, refused by json_path: it was written as ".json.json")
    return json_path(named_output_path(filepath, "bvh_stats.json"))
