"""Build (`bvhlab.build`): export the scene in scope and build a tree with the panel's settings.
From the UI the build runs on a thread (the UI stays live; Esc cancels it); from a script it runs
at once (execute)."""

from __future__ import annotations

import bpy

from . import state
from .background import UI_WORK_THREADS, ModalTaskMixin, TaskCancelled
from .operator_support import build_tree, export_scene, remember_tree, run_reported


class BVHLAB_OT_build(ModalTaskMixin, bpy.types.Operator):
    """Build a BVH over the objects in scope with the chosen split method (Esc cancels)"""

    bl_idname = "bvhlab.build"
    bl_label = "Build BVH"
    bl_options = {"REGISTER"}

    def execute(self, context):
        from bvhlab.blender import SubstituteWarning  # a tree needs no camera or light

        return run_reported(self, context, lambda: self._build(context), quiet=(SubstituteWarning,))

    def invoke(self, context, event):
        from bvhlab.blender import SubstituteWarning

        return run_reported(self, context, lambda: self._start(context), quiet=(SubstituteWarning,))

    def _start(self, context):
        import bvhlab

        self._exported = exported = export_scene(context, require_camera=False)  # bpy: on the UI thread
        s = context.scene.bvhlab
        options = {**s.build_kwargs(), "threads": UI_WORK_THREADS}

        def work(task):
            return bvhlab.build(exported, **options, progress=lambda fraction: task.progress(fraction))

        return self.start_task(context, work, "Building BVH")

    def finish_task(self, context, task):
        return run_reported(self, context, lambda: self._finish(context, task))

    def _finish(self, context, task):
        import bvhlab

        if isinstance(task.error, (bvhlab.BuildCancelled, TaskCancelled)):
            message = "Build cancelled (Esc); the previous tree is kept"
            self.report({"WARNING"}, message)
            state.messages[state.key(context.scene)] = ("WARNING", message)
            return {"CANCELLED"}
        if task.error is not None:
            raise task.error
        return self._done(context, task.result, self._exported)

    def _build(self, context):
        exported = export_scene(context, require_camera=False)  # a tree needs no camera
        return self._done(context, build_tree(context, exported), exported)

    def _done(self, context, bvh, exported):
        remember_tree(context, bvh, exported)
        context.scene.bvhlab.overlay_show = True  # the user pressed Build to see the boxes
        s = bvh.stats
        message = (
            f"Built {s['method']} BVH over {s['primitives']} primitives: {s['nodes']} nodes, "
            f"height {s['height']}, SAH cost {s['sah_cost']:.2f}, {s['build_ms']:.1f} ms"
        )
        self.report({"INFO"}, message)
        state.messages[state.key(context.scene)] = ("INFO", message)
        return {"FINISHED"}
