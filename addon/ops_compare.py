"""Compare methods (`bvhlab.compare`): the report's Table 1 for the open scene — every split method
built and rendered with bvhlab.compare's protocol (the same as `bvhlab compare` on the command
line), with frame time, build time, tree height and SAH cost. From the UI the measurement runs on a
thread (Esc stops it between steps); from a script at once."""

from __future__ import annotations

import bpy

from . import state
from .background import ModalTaskMixin, TaskCancelled
from .operator_support import export_scene, named_output_path, run_reported, temporary_note
from .ops_render import render_size

#: (label, method label of bvhlab.compare): every split method, SAH at the report's 12 and 32 bins.
COMPARE_METHODS = (
    ("Median", "median"),
    ("Mean", "mean"),
    ("Midpoint", "midpoint"),
    ("SAH 12 bins", "sah12"),
    ("SAH 32 bins", "sah32"),
    ("SAH full sweep", "sweep_sah"),
    ("LBVH", "lbvh"),
)


def compare_build_options(settings) -> dict:
    """Every build setting of the panel but the method and its bins, which each Compare row (and
    each of Compare Two Trees' trees) sets."""
    build = settings.build_config().tree_settings()
    return {name: build[name] for name in ("bin_bounds", "axis", "max_leaf_size", "sah_block")}


class BVHLAB_OT_compare(ModalTaskMixin, bpy.types.Operator):
    """Build and render the scene with every split method; show the table (frame time, build time,
    height, SAH cost) in the panel and write it as CSV (Esc stops)"""

    bl_idname = "bvhlab.compare"
    bl_label = "Compare Methods"
    bl_options = {"REGISTER"}

    def execute(self, context):
        def work():
            window_manager = context.window_manager
            window_manager.progress_begin(0, len(COMPARE_METHODS))
            try:
                measure = self._measurement(context)
                return self._done(
                    context,
                    measure(
                        lambda fraction, text: (
                            window_manager.progress_update(int(fraction * len(COMPARE_METHODS))) or True
                        )
                    ),
                )
            finally:
                window_manager.progress_end()

        return run_reported(self, context, work)

    def invoke(self, context, event):
        def start():
            measure = self._measurement(context)  # exports on the UI thread

            def work(task):
                def progress(fraction, text):
                    task.progress(fraction, text)
                    task.check()  # Esc: TaskCancelled at the next step

                return measure(progress)

            return self.start_task(context, work, "Comparing methods")

        return run_reported(self, context, start)

    def finish_task(self, context, task):
        def finish():
            if isinstance(task.error, TaskCancelled):
                message = "Comparison cancelled (Esc)"
                self.report({"WARNING"}, message)
                state.messages[self._scene_key] = ("WARNING", message)
                return {"CANCELLED"}
            if task.error is not None:
                raise task.error
            return self._done(context, task.result)

        return run_reported(self, context, finish, scene_key=self._scene_key)

    def _measurement(self, context):
        """measure(progress) → rows; everything read from bpy is read here, on the UI thread."""
        from bvhlab.compare import measure_methods
        from bvhlab.render import default_renderer

        settings = context.scene.bvhlab
        # the scene measured: the window may show another one by the time the rows come back
        self._scene_key = state.key(context.scene)
        exported = export_scene(context, require_camera=True)
        width, height = render_size(context.scene)
        options = {
            "frames": settings.compare_frames,
            "builds": 1,
            "width": width,
            "height": height,
            "options": settings.render_options(),  # as F12 and the sidebar's Render trace
            "build_options": compare_build_options(settings),
        }
        backend, labels = settings.backend, [method for _, method in COMPARE_METHODS]
        from bvhlab._checks import output_file

        # checked before the measuring (a folder, a file as parent, another suffix, were said only
        # after it: 16 s on a 980K-triangle scene; a helper's probe)
        path = named_output_path(settings.compare_filepath, "bvh_compare.csv")  # .csv added as Export Stats adds .json
        self._csv_path = output_file(path, (".csv",), "table")

        def measure(progress):
            started = []

            def on_step(text: str) -> None:  # "<method>: building" starts each method
                if text.endswith("building"):
                    started.append(text)
                progress(len(started) / len(labels), text)

            return measure_methods(exported, labels, renderer=default_renderer(backend), progress=on_step, **options)

        return measure

    def _done(self, context, rows):
        from bvhlab.compare import write_csv

        labels = {method: label for label, method in COMPARE_METHODS}
        for row in rows:
            row["label"] = labels[row["method"]]
        state.comparisons[self._scene_key] = rows
        path = write_csv(rows, self._csv_path)
        best = min(rows, key=lambda row: row["frame_ms"])
        message = (
            f"Compared {len(rows)} methods; fastest frame: {best['label']} ({best['frame_ms']:.1f} ms); wrote {path}"
            + temporary_note(path)
        )
        self.report({"INFO"}, message)
        state.messages[self._scene_key] = ("INFO", message)
        return {"FINISHED"}
