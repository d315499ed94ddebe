"""The boxes of a two-level tree (issue 34) as the overlays draw them: the TLAS's node boxes (world
space), the BLASes' node boxes moved into the world by each instance, or both, in a depth range
that applies within each level, at most MAX_OVERLAY_BOXES of them (the shallowest TLAS boxes first,
then the BLAS boxes of the first instances; `note` says what was left out). One function,
bvhlab.inspect.levels.shown_boxes, decides them, which Pick Box picks among too; these are its
names for the add-on's viewport overlay (addon/overlay) and the tracers' overlay pass
(`RenderOptions.overlay_level`, _render_scene.py). The tracers' pass at level "tlas" draws the
TLAS's own node boxes, as it draws a flat tree's: every box in the depth range, none left out."""

from __future__ import annotations

from .inspect.levels import LEVELS, MAX_OVERLAY_BOXES, cap_note, world_boxes
from .inspect.levels import ShownBoxes as LevelBoxes
from .inspect.levels import shown_boxes as two_level_boxes

__all__ = [
    "LEVELS",
    "MAX_OVERLAY_BOXES",
    "LevelBoxes",
    "traced_level",
    "traced_cap_note",
    "two_level_boxes",
    "world_boxes",
]


def traced_level(bvh, options) -> tuple | None:
    """(level, depth_min, depth_max) when a render's overlay pass draws other boxes than the tree's
    node boxes (a two-level tree's BLAS boxes, moved into the world); None otherwise (a flat tree,
    the TLAS's boxes, or no overlay). `options`: RenderOptions (overlay_depth, overlay_level)."""
    from .instanced import InstancedBvh

    if options is None or options.overlay_depth is None or options.overlay_level == "tlas":
        return None
    if not isinstance(bvh, InstancedBvh):
        return None
    return (options.overlay_level, *(int(d) for d in options.overlay_depth))


def traced_cap_note(bvh, options) -> str:
    """What the cap (MAX_OVERLAY_BOXES) leaves out of the boxes a render with `options` traces over
    `bvh`, in words ("" when nothing): the note the sidebar shows, for F12 and the viewport (at
    level "tlas" none: the pass draws the TLAS's node boxes, every one in the range)."""
    level = traced_level(bvh, options)
    return "" if level is None else cap_note(bvh, *level)
