"""Where a tree's cost is (issue 35), flat or two-level: Analyse Tree (every node's figures, which
the measure colourings and the Inspect panel read), the Cost panel's breakdown per depth and its
costliest subtrees, and Pick Node (a button of that list picks its node). A two-level tree's
figures are those of the whole tree the TLAS and its instances' mesh trees make together
(bvhlab.inspect.two_level_data), so its depths and costs read as a flat tree's."""

from __future__ import annotations

import bpy
from bpy.props import IntProperty

from . import overlay, state
from .ops_inspect import NO_TREE, inspected_tree

#: Rows of the Cost panel's list: the costliest subtrees at the shown range's top depth.
COSTLIEST = 5
_per_depth: dict = {}  # the tree's serial → its SAH cost per depth (one entry: the tree shown)


class BVHLAB_OT_pick_node(bpy.types.Operator):
    """Pick this node (highlighted in the viewport, its figures in the Inspect panel)"""

    bl_idname = "bvhlab.pick_node"
    bl_label = "Pick Node"
    bl_options = {"REGISTER"}

    node: IntProperty(name="Node", min=0)  # type: ignore[valid-type]
    # A two-level tree's node: -1 for the TLAS's, else the instance whose mesh tree holds it.
    instance: IntProperty(name="Instance", min=-1, default=-1)  # type: ignore[valid-type]

    def execute(self, context):
        built = inspected_tree(context.scene)
        if built is None:
            self.report({"WARNING"}, NO_TREE)
            return {"CANCELLED"}
        picked, problem = self._node(built)
        if problem:
            self.report({"ERROR"}, problem)
            return {"CANCELLED"}
        state.remember_pick(context.scene, built, picked, "node")
        overlay.tag_redraw()
        return {"FINISHED"}

    def _node(self, built):
        """(what to pick, "") or (None, why it does not exist)."""
        bvh = built.bvh
        if not overlay.is_two_level(built):
            if self.instance >= 0:
                return None, "this tree is flat: it has no instances"
            n = bvh.stats["nodes"]
            return (
                (self.node, "") if self.node < n else (None, f"node {self.node} does not exist; the tree has {n} nodes")
            )
        from bvhlab.inspect.levels import TreeNode

        instances = len(bvh.instances[0])
        if self.instance >= instances:
            return None, f"instance {self.instance} does not exist; the scene has {instances} instances"
        if self.instance < 0:
            n = len(bvh.tlas.nodes)
            level = "the TLAS"
        else:
            n = len(bvh.meshes[int(bvh.instances[0][self.instance])].nodes)
            level = f"instance {self.instance}'s mesh tree"
        if self.node >= n:
            return None, f"node {self.node} does not exist; {level} has {n} nodes"
        return (TreeNode("tlas", self.node) if self.instance < 0 else TreeNode("blas", self.node, self.instance)), ""


class BVHLAB_OT_analyse_tree(bpy.types.Operator):
    """Compute every node's figures (SAH share, child overlap, EPO) for the Inspect panel and the
    measure colourings: a second or two for a million nodes"""

    bl_idname = "bvhlab.analyse_tree"
    bl_label = "Analyse Tree"
    bl_options = {"REGISTER"}

    def execute(self, context):
        import time

        built = inspected_tree(context.scene)
        if built is None:
            self.report({"WARNING"}, NO_TREE)
            return {"CANCELLED"}
        start = time.perf_counter()
        data = built.bvh.node_data()
        ms = (time.perf_counter() - start) * 1e3
        if overlay.is_two_level(built):  # the TLAS and each mesh's tree, joined
            nodes = len(data.tlas) + sum(len(d) for d in data.meshes)
            self.report(
                {"INFO"},
                f"Analysed {nodes} nodes (TLAS and {len(data.meshes)} mesh trees) in {ms:.0f} ms: "
                f"SAH {data.sah_cost:.4g} (TLAS {data.tlas.sah_cost:.4g})",
            )
        else:
            self.report(
                {"INFO"}, f"Analysed {len(data)} nodes in {ms:.0f} ms: SAH {data.sah_cost:.4g}, EPO {data.epo_cost:.4g}"
            )
        overlay.tag_redraw()  # a measure colouring waits for the analysis
        return {"FINISHED"}


def sah_per_depth(built) -> list[float]:
    """The shown tree's SAH cost split by depth (bvhlab.compare.tree_stats, and for a two-level
    tree two_level_stats.two_level_sah_cost_per_depth: from the nodes alone, milliseconds), kept
    for the tree's serial so that drawing the panel recomputes nothing."""
    if built.serial not in _per_depth:
        from bvhlab.compare.tree_stats import sah_cost_per_depth

        bvh = built.bvh
        _per_depth.clear()
        if overlay.is_two_level(built):
            from bvhlab.two_level_stats import two_level_sah_cost_per_depth

            meshes = [sah_cost_per_depth(m) for m in bvh.meshes]
            per_depth = two_level_sah_cost_per_depth(bvh.tlas, bvh.instances[0], meshes, bvh.stats["mesh_sah_cost"])
        else:
            per_depth = sah_cost_per_depth(bvh)
        _per_depth[built.serial] = per_depth
    return _per_depth[built.serial]


def costliest(built, depth: int) -> list[tuple[str, int, int]]:
    """The Cost panel's rows: (text, node, instance or -1) of the COSTLIEST subtrees at `depth`,
    largest first; [] until the tree is analysed (drawing never computes node data)."""
    data = built.bvh.cached_node_data()
    if data is None:
        return []
    if not overlay.is_two_level(built):
        nodes = data.costliest_at_depth(depth, COSTLIEST)
        return [(f"Node {int(n)}: {100 * data.sah_share[n]:.2f}%", int(n), -1) for n in nodes]
    rows = []
    for node, cost in data.costliest(COSTLIEST, depth):
        share = f"{100 * cost / data.sah_cost:.2f}%" if data.sah_cost > 0 else "0%"
        name = f"TLAS node {node.node}" if node.level == "tlas" else f"Inst {node.instance} node {node.node}"
        rows.append((f"{name}: {share}", node.node, node.instance))
    return rows


def draw_cost_panel(layout, scene) -> None:
    """The cost breakdown per depth (a bar per depth, its share of the SAH cost) and the costliest
    subtrees at the top depth of the shown range, each a button that picks it."""
    built = inspected_tree(scene)
    if built is None:
        layout.label(text=NO_TREE, icon="INFO")
        return
    per_depth = sah_per_depth(built)
    total = sum(per_depth) or 1.0
    widest = max(per_depth, default=0.0) or 1.0
    col = layout.column(align=True)
    for depth, cost in enumerate(per_depth):
        col.progress(factor=cost / widest, type="BAR", text=f"{depth}: {100 * cost / total:.1f}%")
    if built.bvh.cached_node_data() is None:
        layout.operator(BVHLAB_OT_analyse_tree.bl_idname, icon="VIEWZOOM")
        return
    depth = scene.bvhlab.overlay_depth_min
    layout.label(text=f"Costliest at depth {depth}:")
    col = layout.column(align=True)
    for text, node, instance in costliest(built, depth):
        op = col.operator(BVHLAB_OT_pick_node.bl_idname, text=text)
        op.node, op.instance = node, instance


classes = (BVHLAB_OT_pick_node, BVHLAB_OT_analyse_tree)
