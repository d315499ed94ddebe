"""The viewport overlay: a POST_VIEW draw handler that draws the boxes of the scene's tree in the
panel's depth range (report §3.3). The GPU batch is remade only when the tree or the leaves-only
choice changes; the depth range only picks a slice of it."""

from __future__ import annotations

import bpy

from .. import state

_handle = None
_cached: dict = {"key": None, "batch": None}
_failed: set = set()  # trees whose overlay failed: report once, not on every redraw


def shown_measure(built, measure: str) -> str:
    """The measure the boxes are coloured by: the chosen one once the tree is analysed (drawing
    never computes node data; a two-level tree's figures are its whole tree's:
    bvhlab.inspect.two_level_data), else "depth"."""
    if measure == "depth":
        return "depth"
    return measure if built.bvh.cached_node_data() is not None else "depth"


def is_two_level(built) -> bool:
    """The tree is an instanced scene's (bvhlab.InstancedBvh: TLAS and BLAS boxes)."""
    import bvhlab

    return isinstance(built.bvh, bvhlab.InstancedBvh)


def batch_for(built, leaves_only: bool, measure: str = "depth", level: str = "both", depth_range=(0, 255)):
    """The BoxBatch of a built tree, made on first use and whenever the tree, leaves-only or the
    measure shown changes; for a two-level tree also the level shown and the depth range (its
    table holds only the boxes of the range: overlay/levels.py)."""
    from .batch import BoxBatch

    measure = shown_measure(built, measure)
    two_level = is_two_level(built)
    key = (built.serial, leaves_only, measure) + ((level, tuple(depth_range)) if two_level else ())
    if _cached["key"] != key:
        _cached["batch"] = None  # free the old texture before making the new one
        if two_level:
            _cached["batch"] = BoxBatch(two_level_table(built.bvh, leaves_only, measure, level, depth_range))
        else:
            _cached["batch"] = BoxBatch.from_bvh(built.bvh, leaves_only, measure)
        _cached["key"] = key
    return _cached["batch"]


def two_level_table(bvh, leaves_only: bool, measure: str, level: str, depth_range):
    """The BoxTable of a two-level tree's shown boxes (overlay/levels.py), coloured by `measure`
    of its analysed whole tree (bvhlab.inspect.two_level_data) unless "depth"."""
    from .batch import BoxTable
    from .levels import two_level_boxes

    boxes = two_level_boxes(bvh, level, *depth_range, leaves_only=leaves_only)
    table = BoxTable.from_boxes(boxes.lo, boxes.hi, boxes.depth, boxes.note)
    if measure != "depth":  # each box's value on the heat ramp in the spare column
        table.rows[:, 7], table.legend = bvh.node_data().values(boxes, measure)
    return table


def scene_batch(scene, built):
    """The BoxBatch of the scene's tree as its settings ask for it."""
    settings = scene.bvhlab
    depth_range = (settings.overlay_depth_min, settings.overlay_depth_max)
    return batch_for(built, settings.overlay_leaves_only, settings.overlay_measure, settings.overlay_level, depth_range)


def draw_scene_overlay(scene, view_projection) -> int:
    """Draw the scene's boxes as its settings say; returns the number of boxes drawn."""
    settings = scene.bvhlab
    built = state.tree_for(scene)
    if not settings.overlay_show or built is None:
        return 0
    batch = scene_batch(scene, built)
    return batch.draw(
        view_projection,
        settings.overlay_depth_min,
        settings.overlay_depth_max,
        color=settings.overlay_color,
        color_by_depth=settings.overlay_color_by_depth,
        xray=settings.overlay_xray,
        line_width=settings.overlay_line_width,
    )


def _draw_callback() -> None:
    context = bpy.context
    built = state.tree_for(context.scene)
    if built is None or built.serial in _failed or context.region_data is None:
        return
    try:
        if context.scene.bvhlab.overlay_show:  # the pick is among the boxes shown: none are
            _draw_picked(context.scene)
        if context.space_data.shading.type == "RENDERED" and context.engine == "BVHLAB_WHITTED":
            return  # the engine traces the boxes into its image, depth-correct (report §3.3)
        draw_scene_overlay(context.scene, context.region_data.perspective_matrix)
    except Exception:  # a draw callback must not raise on every redraw; say it once
        import traceback

        traceback.print_exc()
        _failed.add(built.serial)
        state.messages[state.key(context.scene)] = ("ERROR", "the BVH overlay failed to draw; see the console")


#: The picked box's highlight: white, over everything (it is found by clicking through the others).
PICKED_COLOR, PICKED_LINE_WIDTH = (1.0, 1.0, 1.0, 1.0), 3.0


def _draw_picked(scene) -> None:
    """The box picked with Pick Box (ops_inspect.py), its 12 edges drawn over the scene."""
    from ..ops_inspect import picked_box

    box = picked_box(scene)
    if box is None:
        return
    import gpu
    from gpu_extras.batch import batch_for_shader

    from .batch import CUBE_EDGES

    lo, hi = box
    corners = lo + CUBE_EDGES * (hi - lo)
    shader = gpu.shader.from_builtin("UNIFORM_COLOR")
    batch = batch_for_shader(shader, "LINES", {"pos": corners.tolist()})
    gpu.state.depth_test_set("NONE")
    gpu.state.line_width_set(PICKED_LINE_WIDTH)
    shader.uniform_float("color", PICKED_COLOR)
    batch.draw(shader)
    gpu.state.line_width_set(1.0)


def add_handler() -> None:
    global _handle
    if _handle is None:
        _handle = bpy.types.SpaceView3D.draw_handler_add(_draw_callback, (), "WINDOW", "POST_VIEW")


def remove_handler() -> None:
    """Remove the draw handler and free the GPU batch."""
    global _handle
    if _handle is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_handle, "WINDOW")
        _handle = None
    _cached.update(key=None, batch=None)
    _failed.clear()
    from .shader import forget_shader

    forget_shader()


def handler_installed() -> bool:
    return _handle is not None


def tag_redraw() -> None:
    """Ask every 3D viewport to redraw (after a settings or tree change)."""
    window_manager = bpy.context.window_manager
    for window in window_manager.windows if window_manager else ():
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()
