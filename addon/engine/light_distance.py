"""Measure for the scene's Light Distance (BVHLAB_PG_settings.light_distance): the distance the
point light's watts are calibrated by (bvhlab.blender.light), measured at the current frame and
kept in the scene, so that every render job lights its frames alike (a render farm's chunks each
start at a frame of their own, and would each measure at it)."""

from __future__ import annotations

import bpy

from ..operator_support import run_reported


class BVHLAB_OT_measure_light_distance(bpy.types.Operator):
    """Set Light Distance to the current frame's: the median distance from the scene's light to the
    primitives the viewport shows (F12 measures it over what renders, at a render job's first frame)"""

    bl_idname = "bvhlab.measure_light_distance"
    bl_label = "Measure Light Distance"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        return run_reported(self, context, lambda: self._measure(context))

    def _measure(self, context) -> set[str]:
        from bvhlab.blender import LiveScene
        from bvhlab.blender.light import first_light

        depsgraph = context.evaluated_depsgraph_get()
        if first_light(depsgraph, context.view_layer) is None:
            raise ValueError("nothing to measure: the scene has no visible light")
        # exported as F12 exports, from the viewport's evaluation (its visibility and modifier levels)
        live = LiveScene("visible", require_camera=False, allow_empty=True)
        live.sync(depsgraph, context.scene, context.view_layer)
        if live.light_distance is None:
            raise ValueError("nothing to measure: the scene has no visible geometry")
        context.scene.bvhlab.light_distance = live.light_distance
        self.report({"INFO"}, f"Light distance {live.light_distance:.4g} (frame {context.scene.frame_current})")
        return {"FINISHED"}
