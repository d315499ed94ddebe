"""Which pixels of the frame a final render traces, and where they go: the whole frame, or
Blender's render border.

Blender renders a border as a Render Result of the border's size, with or without Crop to Render
Region: it places the border's pixels in the full frame afterwards when not cropping (pipeline.cc
render_init_from_main: the border in pixels is `border.min * size` truncated, in float32; then
render_result_uncrop). So the engine's result is always the border's rectangle, begun at (0, 0),
and the camera traces that part of its frame (bvhlab.Camera.region).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FinalFrame:
    """A frame of frame_width × frame_height pixels (the engine's resolution, percentage applied)
    of which the rectangle at (x, y) from its bottom-left corner, width × height, is traced."""

    frame_width: int
    frame_height: int
    x: int
    y: int
    width: int
    height: int

    @property
    def region(self) -> tuple[float, float, float, float]:
        """The traced rectangle as bvhlab.Camera.region: fractions of the frame from its top left."""
        fw, fh = self.frame_width, self.frame_height
        top = fh - (self.y + self.height)
        return (self.x / fw, top / fh, (self.x + self.width) / fw, (top + self.height) / fh)

    @property
    def whole(self) -> bool:
        return (self.width, self.height) == (self.frame_width, self.frame_height)


def final_frame(render, frame_width: int, frame_height: int) -> FinalFrame:
    """The traced part of a frame_width × frame_height frame for scene.render's border settings.
    Raises ValueError for a border with no pixels."""
    if not render.use_border:
        return FinalFrame(frame_width, frame_height, 0, 0, frame_width, frame_height)

    def pixels(fraction: float, size: int) -> int:  # C's float product, truncated to int
        return int(np.float32(fraction) * np.float32(size))

    x0, x1 = pixels(render.border_min_x, frame_width), pixels(render.border_max_x, frame_width)
    y0, y1 = pixels(render.border_min_y, frame_height), pixels(render.border_max_y, frame_height)
    if x1 <= x0 or y1 <= y0:
        raise ValueError(
            f"the render border covers no pixel of the {frame_width} × {frame_height} frame: widen it "
            f"or turn Render Region off"
        )
    return FinalFrame(frame_width, frame_height, x0, y0, x1 - x0, y1 - y0)
