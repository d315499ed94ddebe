"""A rendered float image → the Blender Image "BVH Render", shown in any open Image Editor."""

from __future__ import annotations

import bpy
import numpy as np

IMAGE_NAME = "BVH Render"


def show_render(context, pixels: np.ndarray, name: str = IMAGE_NAME):
    """Write `pixels` (float (height, width, 4), row 0 = top, linear RGB) into the Image `name`
    (default "BVH Render"; created or resized as needed) and show it in every open Image Editor."""
    height, width = pixels.shape[:2]
    image = bpy.data.images.get(name)
    if image is None:
        image = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True)
    elif tuple(image.size) != (width, height):
        image.scale(width, height)
    # Blender's row 0 is the bottom of the picture.
    image.pixels.foreach_set(np.ascontiguousarray(pixels[::-1], np.float32).reshape(-1))
    image.update()
    for window in context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == "IMAGE_EDITOR":
                area.spaces.active.image = image
                area.tag_redraw()
    return image
