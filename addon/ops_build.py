"""Build (`bvhlab.build`): export the scene in scope and build a tree with the panel's settings."""
from __future__ import annotations

import bpy

from . import state
from .operator_support import build_tree, export_scene, remember_tree, run_reported


class BVHLAB_OT_build(bpy.types.Operator):
    """Build a BVH over the objects in scope with the chosen split method"""
    bl_idname = "bvhlab.build"
    bl_label = "Build BVH"
    bl_options = {"REGISTER"}

    def execute(self, context):
        from bvhlab.blender import SubstituteWarning  # a tree needs no camera or light

        return run_reported(self, context, lambda: self._build(context), quiet=(SubstituteWarning,))

    def _build(self, context):
        exported = export_scene(context, require_camera=False)  # a tree needs no camera
        bvh = build_tree(context, exported)
        remember_tree(context, bvh, exported)
        context.scene.bvhlab.overlay_show = True  # the user pressed Build to see the boxes
        s = bvh.stats
        message = (f"Built {s['method']} BVH over {s['primitives']} primitives: {s['nodes']} nodes, "
                   f"height {s['height']}, SAH cost {s['sah_cost']:.2f}, {s['build_ms']:.1f} ms")
        self.report({"INFO"}, message)
        state.messages[state.key(context.scene)] = ("INFO", message)
        return {"FINISHED"}
