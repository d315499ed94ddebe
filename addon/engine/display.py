"""Drawing a traced viewport frame with Blender's `gpu` module (UI thread, inside view_draw)."""
from __future__ import annotations

import time

import numpy as np


class FrameDisplay:
    """The texture of the latest frame; uploaded again only when a new frame arrives."""

    def __init__(self):
        self.texture = None
        self.serial = None  # id of the frame in the texture
        self.upload_ms = 0.0
        self.draw_ms = 0.0

    def draw(self, engine, blender_scene, frame) -> None:
        """Draw `frame` (a viewport.ViewFrame) into the region at its frustum's rectangle, through
        the scene's view transform like any Render Result (Blender colour-manages the viewport)."""
        import gpu
        from gpu_extras.presets import draw_texture_2d

        started = time.perf_counter()
        if id(frame) != self.serial:
            self._upload(frame.image)
            self.serial = id(frame)
            self.upload_ms = (time.perf_counter() - started) * 1e3
        x, y, width, height = frame.request.frustum.draw_rect
        gpu.state.blend_set("ALPHA_PREMULT")
        engine.bind_display_space_shader(blender_scene)
        try:
            draw_texture_2d(self.texture, (x, y), width, height)
        finally:
            engine.unbind_display_space_shader()
            gpu.state.blend_set("NONE")
        self.draw_ms = (time.perf_counter() - started) * 1e3

    def _upload(self, image: np.ndarray) -> None:
        import gpu

        height, width = image.shape[:2]
        pixels = np.ascontiguousarray(image[::-1], np.float32).reshape(-1)  # GPU row 0 is the bottom
        self.texture = None  # free the old texture first
        self.texture = gpu.types.GPUTexture((width, height), format="RGBA32F",
                                            data=gpu.types.Buffer("FLOAT", pixels.size, pixels))
