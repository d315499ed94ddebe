"""Build (`bvhlab.build`): export the scene in scope and build a tree with the panel's settings.
From the UI the build runs on a thread (the UI stays live; Esc cancels it); from a script it runs
at once (execute).

The settings are taken when the build starts: a tree is labelled with what it was built with,
whatever the panel shows by the time the thread is done. Build always builds (that is what the
button is for); the tree goes into the one cache of trees (trees.py), where F12, the viewport and
the sidebar's Render find it. One build per scene at a time: starting
another (a second press, or a script) cancels the one running, whose tree is then never kept, so
the tree kept is always the one of the last build started (issue 39)."""

from __future__ import annotations

import bpy

from . import follow, state
from .background import UI_WORK_THREADS, BackgroundTask, ModalTaskMixin, TaskCancelled
from .operator_support import export_scene, remember_tree, run_reported, window_progress
from .trees import cache, key_of


def _take_over(scene_key: int, owner) -> bool:
    """Make `owner` the scene's current build; cancel the one running before. True if there was one."""
    running = state.builds.get(scene_key)
    state.builds[scene_key] = owner
    if isinstance(running, BackgroundTask) and not running.done:
        running.cancel()
        return True
    return False


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
        # the scene it builds for: the window may show another one by the time it ends (its tree was
        # then thrown away as "replaced", and this scene kept a build that never ended: probe)
        self._scene_key = state.key(context.scene)
        follow.export_taken(self._scene_key, context.view_layer, context.scene.bvhlab.scope)
        self._key = key = key_of(context.scene)  # the settings as they are now, not when it ends
        config = key.config.replace(threads=UI_WORK_THREADS)

        def work(task):
            return bvhlab.build(exported, config=config, progress=lambda fraction: task.progress(fraction))

        started = self.start_task(context, work, "Building BVH")
        if _take_over(state.key(context.scene), self._task):
            self.report({"INFO"}, "The build running before was cancelled: this one replaces it")
        return started

    def finish_task(self, context, task):
        return run_reported(self, context, lambda: self._finish(context, task), scene_key=self._scene_key)

    def _finish(self, context, task):
        import bvhlab

        key = self._scene_key
        scene = next((s for s in bpy.data.scenes if state.key(s) == key), None)
        if scene is None:  # deleted while it built
            state.builds.pop(key, None)
            self.report({"WARNING"}, "The scene was deleted while its BVH was built; the tree is not kept")
            return {"CANCELLED"}
        if state.builds.get(key) is not task:  # replaced by a build started after it
            self.report({"INFO"}, "Build replaced by the one started after it; its tree is not kept")
            return {"CANCELLED"}
        del state.builds[key]
        if isinstance(task.error, (bvhlab.BuildCancelled, TaskCancelled)):
            message = "Build cancelled (Esc); the previous tree is kept"
            self.report({"WARNING"}, message)
            state.messages[key] = ("WARNING", message)
            return {"CANCELLED"}
        if task.error is not None:
            raise task.error
        cache.tree(self._key).store(task.result, self._exported)
        return self._done(context, self._key, scene)

    def _build(self, context):
        import bvhlab

        key = state.key(context.scene)
        _take_over(key, self)  # a build started from the UI before this one is cancelled
        try:
            tree_key = key_of(context.scene)
            exported = export_scene(context, require_camera=False)  # a tree needs no camera
            follow.export_taken(key, context.view_layer, context.scene.bvhlab.scope)
            with window_progress(context) as progress:
                bvh = bvhlab.build(exported, config=tree_key.config, progress=progress)
            cache.tree(tree_key).store(bvh, exported)
            return self._done(context, tree_key, context.scene)
        finally:
            if state.builds.get(key) is self:
                del state.builds[key]

    def _done(self, context, tree_key, scene):
        built = remember_tree(context, tree_key, scene)
        scene.bvhlab.overlay_show = True  # the user pressed Build to see the boxes
        s = built.bvh.stats
        message = (
            f"Built {s['method']} BVH over {s['primitives']} primitives: {s['nodes']} nodes, "
            f"height {s['height']}, SAH cost {s['sah_cost']:.2f}, {s['build_ms']:.1f} ms"
        )
        if "instances" in s:  # a two-level tree (issue 34): each mesh stored once
            flattened = s["triangles_flattened"]
            message += f" ({s['instances']:,} instances of {s['meshes']} meshes: {flattened:,} triangles flattened)"
        self.report({"INFO"}, message)
        state.messages[state.key(scene)] = ("INFO", message)
        return {"FINISHED"}
