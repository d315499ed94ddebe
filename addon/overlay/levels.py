"""The boxes of a two-level tree as the overlay draws them: `bvhlab.overlay_levels` (one definition,
shared with the tracers' overlay pass), under the name the add-on has used."""

from bvhlab.overlay_levels import LEVELS, MAX_OVERLAY_BOXES, LevelBoxes, two_level_boxes, world_boxes

__all__ = ["LEVELS", "MAX_OVERLAY_BOXES", "LevelBoxes", "two_level_boxes", "world_boxes"]
