"""Esc for the Rendered viewport: cancel the build a viewport's worker is running."""

from __future__ import annotations

import bpy


class BVHLAB_OT_viewport_cancel(bpy.types.Operator):
    """Stop the BVH build and tracing of the Rendered viewports (until the scene changes)"""

    bl_idname = "bvhlab.viewport_cancel"
    bl_label = "Cancel Viewport Render"
    bl_options = {"INTERNAL"}

    @classmethod
    def poll(cls, context):
        from .viewport import busy_sessions

        return bool(busy_sessions())

    def execute(self, context):
        from .viewport import busy_sessions

        for session in busy_sessions():
            session.cancel()
        self.report({"INFO"}, "Cancelled the viewport's BVH build")
        return {"FINISHED"}
