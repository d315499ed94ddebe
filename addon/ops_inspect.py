"""Inspecting the tree in the viewport (issue 35): click to pick the box under the cursor (the rule
of bvhlab.inspect.pick: the deepest shown box the mouse ray enters first, or the leaf it hits),
step to its parent, children or sibling, and frame it. The sidebar's Inspect panel shows the
picked node's figures (Bvh.node_data). A two-level tree (an instanced scene) is picked among the
boxes the overlay shows of it (TLAS, BLAS moved into the world, or both: Viewport Boxes ▸ Level);
a pick is then a bvhlab.inspect.levels.TreeNode, and the steps cross between the levels (a BLAS
root's parent is its instance's TLAS leaf, a TLAS leaf's children its instances' BLAS roots)."""

from __future__ import annotations

import bpy
from bpy.props import EnumProperty, FloatVectorProperty

from . import overlay, state
from .operator_support import run_reported

#: What a tree-less inspect operator says.
NO_TREE = "Build a tree first (BVH ▸ Build)"


def inspected_tree(scene):
    """The scene's tree as Inspect sees it (state.BuiltTree, flat or two-level), or None."""
    return state.tree_for(scene)


def _shown_range(scene, built) -> tuple[int, int]:
    settings = scene.bvhlab
    return settings.overlay_depth_min, min(settings.overlay_depth_max, built.height - 1)


def node_view(built, picked):
    """What the panel, the steps and the highlight need of a picked node: (NodeData of its tree,
    its index there, world lo, world hi, its name in words)."""
    if not overlay.is_two_level(built):
        data = built.bvh.node_data(epo=False)  # the whole data where analysed (Bvh.node_data)
        return data, picked, data.lo[picked], data.hi[picked], f"{'Leaf' if data.left[picked] < 0 else 'Node'} {picked}"
    from bvhlab.inspect.pick import node_world_box

    bvh = built.bvh
    lo, hi = node_world_box(bvh, picked)
    if picked.level == "tlas":
        data = bvh.tlas_node_data()
        what = "leaf" if data.left[picked.node] < 0 else "node"
        return data, picked.node, lo, hi, f"TLAS {what} {picked.node}"
    data = bvh.meshes[int(bvh.instances[0][picked.instance])].node_data(epo=False)
    what = "leaf" if data.left[picked.node] < 0 else "node"
    return data, picked.node, lo, hi, f"Instance {picked.instance} · BLAS {what} {picked.node}"


def whole_tree_figures(built, picked, data=None) -> dict | None:
    """The picked node's figures in the whole tree (depth, primitives under it, subtree SAH, its
    share of the tree's SAH cost `of`): a flat tree's own (from `data`, node_view's NodeData, where
    given: the figures beside it are then of one version of a tree the follow refits); a two-level
    tree's as the Cost panel and `bvhlab inspect --node` give them (TwoLevelNodeData.figures: a mesh
    tree's node weighed by its instance, a TLAS node with its instances' trees; the panel showed the
    TLAS's or the mesh tree's own, every instance of a mesh at the same share), once the tree is
    analysed (None before)."""
    if not overlay.is_two_level(built):
        data = data if data is not None else built.bvh.node_data(epo=False)
        return {**data.node(picked), "of": data.sah_cost}
    analysed = built.bvh.cached_node_data()
    if analysed is None:
        return None
    return {**analysed.figures(picked), "of": analysed.sah_cost}


def _report_pick(operator, built, picked) -> None:
    data, n, _, _, name = node_view(built, picked)
    whole = whole_tree_figures(built, picked, data)
    if whole is None:  # a two-level tree not analysed: its own tree's figures, said so
        where = "the TLAS" if picked.level == "tlas" else "its mesh tree"
        figures = f"depth {int(data.depth[n])} in {where}, {int(data.prim_count[n])} primitives"
    else:
        figures = (
            f"depth {whole['depth']}, {whole['prim_count']} primitives, {100 * whole['sah_share']:.2f}% of the SAH cost"
        )
    operator.report({"INFO"}, f"Picked {name} ({figures})")


def _traced_view(context) -> bool:
    """Whether the 3D viewport picked in shows bvhlab's traced picture (Rendered shading, this engine)."""
    from .engine.engine import ENGINE_ID

    space = getattr(context, "space_data", None)
    shading = getattr(space, "shading", None)
    return shading is not None and shading.type == "RENDERED" and context.scene.render.engine == ENGINE_ID


def pick_ray(operator, context, origin, direction) -> set[str]:
    """Pick with one ray (world space) on the scene's tree and remember it for the panel."""
    from bvhlab.inspect.pick import pick, pick_two_level

    scene = context.scene
    built = inspected_tree(scene)
    if built is None:
        operator.report({"WARNING"}, NO_TREE)
        return {"CANCELLED"}
    settings = scene.bvhlab
    if not settings.overlay_show:  # what is picked is the deepest box drawn: none is
        operator.report({"INFO"}, "No box under the cursor (the boxes are hidden: show them to pick one)")
        return {"CANCELLED"}
    shown = _shown_range(scene, built)
    if shown[0] > shown[1]:  # Min depth below the tree's deepest level: no box is drawn to pick
        operator.report({"INFO"}, "No box under the cursor (no box is drawn at these depths)")
        return {"CANCELLED"}
    # in the Rendered viewport the picture is the tracer's: what the ray reaches is what camera rays
    # see (a surface hidden from them passed by); elsewhere Blender draws every surface
    seen = built.scene if _traced_view(context) else None
    if overlay.is_two_level(built):
        got = pick_two_level(
            built.bvh,
            origin,
            direction,
            settings.overlay_level,
            shown,
            leaves_only=settings.overlay_leaves_only,
            scene=seen,
        )
        picked, how = got.box, got.how
    else:
        got = pick(built.bvh, origin, direction, shown, leaves_only=settings.overlay_leaves_only, scene=seen)
        picked, how = got.node, got.how
    if picked is None:
        state.picked.pop(state.key(scene), None)
        operator.report({"INFO"}, "No box under the cursor")
    else:
        state.remember_pick(scene, built, picked, how)
        _report_pick(operator, built, picked)
    overlay.tag_redraw()
    return {"FINISHED"}


class BVHLAB_OT_pick_box(bpy.types.Operator):
    """Click in the 3D viewport to pick the box under the cursor; Esc or right-click to stop"""

    bl_idname = "bvhlab.pick_box"
    bl_label = "Pick Box"
    bl_options = {"REGISTER"}

    # For scripts: pick with this ray (world space) instead of waiting for a click.
    origin: FloatVectorProperty(name="Origin", size=3, options={"SKIP_SAVE"})  # type: ignore[valid-type]
    direction: FloatVectorProperty(name="Direction", size=3, options={"SKIP_SAVE"})  # type: ignore[valid-type]

    def execute(self, context):
        if not any(self.direction):
            self.report({"ERROR"}, "give a direction, or click in the viewport (invoke)")
            return {"CANCELLED"}
        return run_reported(self, context, lambda: pick_ray(self, context, self.origin, self.direction))

    def invoke(self, context, event):
        if context.area is None or context.area.type != "VIEW_3D":
            self.report({"WARNING"}, "Pick Box works in a 3D viewport")
            return {"CANCELLED"}
        if inspected_tree(context.scene) is None:
            self.report({"WARNING"}, NO_TREE)
            return {"CANCELLED"}
        context.window_manager.modal_handler_add(self)
        context.area.header_text_set("Pick Box: click a box · Esc or right-click to stop")
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        over = _over_viewport(context.area, context.region, event)
        if event.type == "ESC" or (event.type == "RIGHTMOUSE" and over):
            if context.area is not None:
                context.area.header_text_set(None)
            return {"FINISHED"}
        if event.type == "LEFTMOUSE" and event.value == "PRESS":
            region, view = context.region, context.region_data
            if not over or view is None:
                return {"PASS_THROUGH"}  # the sidebar, the header, another area: Blender's click
            from bpy_extras import view3d_utils

            xy = (event.mouse_region_x, event.mouse_region_y)
            origin = view3d_utils.region_2d_to_origin_3d(region, view, xy)
            direction = view3d_utils.region_2d_to_vector_3d(region, view, xy)
            run_reported(self, context, lambda: pick_ray(self, context, origin, direction))
            return {"RUNNING_MODAL"}
        return {"PASS_THROUGH"}  # orbit, zoom and the rest of the window keep working


def _inside(region, event) -> bool:
    return region.x <= event.mouse_x < region.x + region.width and region.y <= event.mouse_y < region.y + region.height


def _over_viewport(area, region, event) -> bool:
    """Whether the event is over the drawing of the viewport Pick Box started in: inside its region
    (the modal's context keeps it wherever the mouse is) and under none of the area's regions drawn
    over it (the sidebar, the toolbar and the headers overlap the view in Blender 4.2+)."""
    if area is None or region is None or region.type != "WINDOW" or not _inside(region, event):
        return False
    return not any(r.type != "WINDOW" and r.width > 1 and r.height > 1 and _inside(r, event) for r in area.regions)


STEPS = [
    ("PARENT", "Parent", "The picked node's parent"),
    ("LEFT", "Child 1", "The picked node's first child"),
    ("RIGHT", "Child 2", "The picked node's second child"),
    ("SIBLING", "Sibling", "The other child of the picked node's parent"),
]


class BVHLAB_OT_pick_step(bpy.types.Operator):
    """Pick the picked node's parent, a child or its sibling"""

    bl_idname = "bvhlab.pick_step"
    bl_label = "Step"
    bl_options = {"REGISTER"}

    step: EnumProperty(name="Step", items=STEPS)  # type: ignore[valid-type]

    def execute(self, context):
        scene, built = context.scene, inspected_tree(context.scene)
        node = state.picked_node(scene)
        if built is None or node is None:
            self.report({"WARNING"}, "Pick a box first")
            return {"CANCELLED"}
        if overlay.is_two_level(built):
            target = two_level_step(built.bvh, node, self.step)
        else:
            target = flat_step(built.bvh.node_data(epo=False), node, self.step)
        if target is None:
            self.report({"WARNING"}, f"{node_view(built, node)[4]} has no {self.step.lower()}")
            return {"CANCELLED"}
        state.remember_pick(scene, built, target, "step")
        overlay.tag_redraw()
        return {"FINISHED"}


def flat_step(data, node: int, step: str) -> int | None:
    """The node a step leads to in one tree (bvhlab.inspect.NodeData), or None."""
    parent = int(data.parent[node])
    sibling = -1 if parent < 0 else int(data.right[parent] if data.left[parent] == node else data.left[parent])
    target = {"PARENT": parent, "LEFT": int(data.left[node]), "RIGHT": int(data.right[node]), "SIBLING": sibling}[step]
    return None if target < 0 else target


def two_level_step(bvh, picked, step: str):
    """The TreeNode a step leads to in a two-level tree, or None: within a level as flat_step;
    from a BLAS root up to the TLAS leaf holding its instance, and from a TLAS leaf down to its
    instances' BLAS roots (Child 1: its first instance's, Child 2: its second's)."""
    from bvhlab.inspect.levels import TreeNode

    if picked.level == "tlas":
        data = bvh.tlas_node_data()
        if data.left[picked.node] < 0 and step in ("LEFT", "RIGHT"):
            instances = bvh.tlas_leaf_instances(picked.node)
            k = 0 if step == "LEFT" else 1
            return TreeNode("blas", 0, int(instances[k])) if k < len(instances) else None
        target = flat_step(data, picked.node, step)
        return None if target is None else TreeNode("tlas", target)
    mesh = bvh.meshes[int(bvh.instances[0][picked.instance])]
    if picked.node == 0 and step == "PARENT":
        leaf = bvh.tlas_leaf_of(picked.instance)
        return TreeNode("tlas", leaf) if leaf >= 0 else None
    target = flat_step(mesh.node_data(epo=False), picked.node, step)
    return None if target is None else TreeNode("blas", target, picked.instance)


class BVHLAB_OT_frame_picked(bpy.types.Operator):
    """Frame the picked box in the 3D viewports"""

    bl_idname = "bvhlab.frame_picked"
    bl_label = "Frame This Box"
    bl_options = {"REGISTER"}

    def execute(self, context):
        from mathutils import Vector

        built, node = inspected_tree(context.scene), state.picked_node(context.scene)
        if built is None or node is None:
            self.report({"WARNING"}, "Pick a box first")
            return {"CANCELLED"}
        _, _, lo, hi, _ = node_view(built, node)
        lo, hi = Vector(lo.tolist()), Vector(hi.tolist())
        framed = 0
        screen = context.window.screen if context.window else None
        for area in screen.areas if screen else ():
            if area.type == "VIEW_3D":
                view = area.spaces.active.region_3d
                view.view_location = (lo + hi) / 2
                view.view_distance = max((hi - lo).length, 1e-6) * 1.2
                area.tag_redraw()
                framed += 1
        if not framed:
            self.report({"WARNING"}, "No 3D viewport to frame the box in")
            return {"CANCELLED"}
        return {"FINISHED"}


def picked_box(scene):
    """(lo, hi) of the picked box, for the overlay's highlight, or None."""
    built, node = inspected_tree(scene), state.picked_node(scene)
    if built is None or node is None:
        return None
    return node_view(built, node)[2:4]


def draw_inspect_panel(layout, scene) -> None:
    """The sidebar's Inspect panel body: Pick Box, and the picked node's figures and steps."""
    layout.operator(BVHLAB_OT_pick_box.bl_idname, icon="RESTRICT_SELECT_OFF")
    built, node = inspected_tree(scene), state.picked_node(scene)
    if built is None or node is None:
        layout.label(text="Pick Box, then click a box", icon="INFO")
        return
    picked = node
    data, node, lo, hi, name = node_view(built, picked)
    leaf = data.left[node] < 0
    col = layout.column(align=True)
    whole = whole_tree_figures(built, picked, data)
    if overlay.is_two_level(built):  # short lines: the sidebar is narrow
        col.label(text=name)
        where = "the TLAS" if picked.level == "tlas" else "its mesh tree"
        depth = f"Depth {int(data.depth[node])} in {where}"
        col.label(text=depth if whole is None else f"{depth}, {whole['depth']} in the tree")
    else:
        col.label(text=f"{name} · depth {int(data.depth[node])}")
    if whole is None:  # a two-level tree not analysed yet: its own tree's figures only
        under = "Instances" if picked.level == "tlas" else "Primitives"
        col.label(text=f"{under} under it: {int(data.prim_count[node])}")
        col.label(text="Analyse Tree for its share of the SAH", icon="INFO")
    else:
        col.label(text=f"Primitives under it: {whole['prim_count']}")
        share = f"{100 * whole['sah_share']:.2f}% of {whole['of']:.4g}"
        col.label(text=f"Subtree SAH: {whole['subtree_sah']:.4g} ({share})")
    col.label(text=f"Own SAH term: {data.sah_term[node]:.4g}")
    if not leaf:
        col.label(text=f"Child overlap: {data.child_overlap[node]:.3f}")
    if data.has_epo:  # made by Analyse Tree (a pick does not wait for the EPO pass)
        col.label(text=f"EPO term: {data.epo[node]:.4g} (tree {data.epo_cost:.4g})")
    size = hi - lo  # in the world (a BLAS box moved by its instance)
    col.label(text="Size: " + " × ".join(f"{v:.3g}" for v in size))
    row = layout.row(align=True)
    for step, label, _ in STEPS:
        row.operator(BVHLAB_OT_pick_step.bl_idname, text=label).step = step
    layout.operator(BVHLAB_OT_frame_picked.bl_idname, icon="ZOOM_SELECTED")


classes = (BVHLAB_OT_pick_box, BVHLAB_OT_pick_step, BVHLAB_OT_frame_picked)
