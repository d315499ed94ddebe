"""Fresh SAH (`bvhlab.fresh_sah`): the SAH cost a fresh build over the current geometry would give,
next to the tree's own after its updates in place (refit, partial, adaptive: issue 34). It costs a
build, so it runs on demand (a button), never per frame; the stats panel shows it until the tree
changes."""

from __future__ import annotations

import bpy

from . import state
from .operator_support import run_reported


class BVHLAB_OT_fresh_sah(bpy.types.Operator):
    """Build the scene's trees afresh (not kept) to compare their SAH cost with the current tree's"""

    bl_idname = "bvhlab.fresh_sah"
    bl_label = "SAH of a Fresh Build"
    bl_options = {"REGISTER"}

    def execute(self, context):
        return run_reported(self, context, lambda: self._measure(context))

    def _measure(self, context):
        from . import follow

        follow.settle(state.key(context.scene))  # the tree the follow is updating, once it has
        built = state.tree_for(context.scene)
        if built is None:
            self.report({"WARNING"}, "Build a tree first (BVH ▸ Build)")
            return {"CANCELLED"}
        fresh = built.tree.fresh_sah_cost()
        current = built.bvh.stats["sah_cost"]
        ratio = f" ({current / fresh:.3f}×)" if fresh > 0 else ""  # an emptied scene's tree costs 0
        message = f"SAH cost {current:.2f}; a fresh build's {fresh:.2f}{ratio}"
        if built.behind:  # both over the geometry the tree holds (state.BuiltTree.behind)
            message += "; both over the tree's geometry: the scene changed since"
        self.report({"INFO"}, message)
        state.messages[state.key(context.scene)] = ("INFO", message)
        return {"FINISHED"}
