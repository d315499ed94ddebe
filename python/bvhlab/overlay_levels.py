"""The boxes of a two-level tree (issue 34) as the overlays draw them: the TLAS's node boxes (world
space), the BLASes' node boxes moved into the world by each instance, or both, in a depth range
that applies within each level, at most MAX_OVERLAY_BOXES of them (`note` says how many instances'
BLAS boxes were kept). One function, bvhlab.inspect.levels.shown_boxes, decides them, which Pick
Box picks among too; these are its names for the add-on's viewport overlay (addon/overlay) and the
tracers' overlay pass (`RenderOptions.overlay_level`, _render_scene.py)."""

from __future__ import annotations

from .inspect.levels import LEVELS, MAX_OVERLAY_BOXES, world_boxes
from .inspect.levels import ShownBoxes as LevelBoxes
from .inspect.levels import shown_boxes as two_level_boxes

__all__ = ["LEVELS", "MAX_OVERLAY_BOXES", "LevelBoxes", "two_level_boxes", "world_boxes"]
