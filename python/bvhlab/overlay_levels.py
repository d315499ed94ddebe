"""The boxes of a two-level tree (issue 34) as the overlays draw them: the TLAS's node boxes (world
space), the BLASes' node boxes moved into the world by each instance, or both, in a depth range
that applies within each level, at most MAX_OVERLAY_BOXES of them (the panel says how many
instances' BLAS boxes were kept). Which boxes these are is one function,
bvhlab.inspect.levels.shown_boxes, which Pick Box picks among too; this is its box list for the
add-on's viewport overlay (addon/overlay) and the tracers' overlay pass
(`RenderOptions.overlay_level`, _render_scene.py)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .inspect.levels import LEVELS, MAX_OVERLAY_BOXES, shown_boxes, world_boxes

__all__ = ["LEVELS", "MAX_OVERLAY_BOXES", "LevelBoxes", "two_level_boxes", "world_boxes"]


@dataclass
class LevelBoxes:
    """Boxes sorted by depth (within their own level): lo, hi (K,3) float32, depth (K,) uint8;
    `instances_shown` of `instances` have their BLAS boxes among them."""

    lo: np.ndarray
    hi: np.ndarray
    depth: np.ndarray
    instances_shown: int
    instances: int

    @property
    def note(self) -> str:
        """What the cap left out, in words ("" when nothing)."""
        if self.instances_shown == self.instances:
            return ""
        return (
            f"BLAS boxes of {self.instances_shown:,} of {self.instances:,} instances "
            f"(at most {MAX_OVERLAY_BOXES:,} boxes)"
        )


def two_level_boxes(
    bvh, level: str, depth_min: int, depth_max: int, leaves_only: bool = False, cap: int = MAX_OVERLAY_BOXES
) -> LevelBoxes:
    """The boxes of `bvh` (a bvhlab.InstancedBvh) that the overlay draws for `level` ("tlas",
    "blas", "both") in the depth range, at most `cap` of them."""
    shown = shown_boxes(bvh, level, depth_min, depth_max, leaves_only, cap)
    return LevelBoxes(shown.lo, shown.hi, shown.depth, shown.instances_shown, shown.instances)
