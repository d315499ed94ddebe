"""Drawing a traced viewport frame with Blender's `gpu` module (UI thread, inside view_draw).

The frame is drawn with a shader that fetches texels by pixel position (nearest, no filtering):
Blender's builtin image shader filters linearly, and the region's pixel-space projection puts
fragment centres a fraction of a pixel off the texel centres, so a full-resolution frame would
come out blurred by ~1% of each neighbour. Previews, smaller than the region, show their pixels as
blocks, as Cycles' viewport does at a coarse pixel size. Blender applies the scene's view transform
to the whole viewport afterwards, so the texture holds linear values, like a Render Result."""

from __future__ import annotations

import time

import numpy as np

_VERTEX = """
void main()
{
  gl_Position = projection * vec4(rect.xy + position * rect.zw, 0.0, 1.0);
}
"""

_FRAGMENT = """
void main()
{
  ivec2 size = textureSize(image, 0);
  vec2 local = (gl_FragCoord.xy - rect.xy) / rect.zw;
  ivec2 texel = clamp(ivec2(floor(local * vec2(size))), ivec2(0), size - ivec2(1));
  frag_color = texelFetch(image, texel, 0);
}
"""

_shader = None


def _frame_shader():
    global _shader
    if _shader is None:
        import gpu

        info = gpu.types.GPUShaderCreateInfo()
        info.vertex_in(0, "VEC2", "position")
        info.push_constant("MAT4", "projection")
        info.push_constant("VEC4", "rect")
        info.sampler(0, "FLOAT_2D", "image")
        info.fragment_out(0, "VEC4", "frag_color")
        info.vertex_source(_VERTEX)
        info.fragment_source(_FRAGMENT)
        _shader = gpu.shader.create_from_info(info)
    return _shader


def forget_shader() -> None:
    global _shader
    _shader = None


class FrameDisplay:
    """The texture of the latest frame; uploaded again only when a new frame arrives."""

    def __init__(self):
        self.texture = None
        self.batch = None
        self.serial = None  # id of the frame in the texture
        self.upload_ms = 0.0
        self.draw_ms = 0.0

    def draw(self, frame) -> None:
        """Draw `frame` (a viewport.ViewFrame) into the region at its frustum's rectangle."""
        import gpu

        started = time.perf_counter()
        if id(frame) != self.serial:
            self._upload(frame.image)
            self.serial = id(frame)
            self.upload_ms = (time.perf_counter() - started) * 1e3
        shader = _frame_shader()
        if self.batch is None:
            from gpu_extras.batch import batch_for_shader

            self.batch = batch_for_shader(shader, "TRI_FAN", {"position": ((0, 0), (1, 0), (1, 1), (0, 1))})
        shader.bind()
        shader.uniform_float("projection", gpu.matrix.get_projection_matrix() @ gpu.matrix.get_model_view_matrix())
        shader.uniform_float("rect", tuple(float(v) for v in frame.request.frustum.draw_rect))
        shader.uniform_sampler("image", self.texture)
        gpu.state.blend_set("ALPHA_PREMULT")
        try:
            self.batch.draw(shader)
        finally:
            gpu.state.blend_set("NONE")
        self.draw_ms = (time.perf_counter() - started) * 1e3

    def _upload(self, image: np.ndarray) -> None:
        import gpu

        height, width = image.shape[:2]
        pixels = np.ascontiguousarray(image[::-1], np.float32).reshape(-1)  # GPU row 0 is the bottom
        self.texture = None  # free the old texture first
        self.texture = gpu.types.GPUTexture(
            (width, height), format="RGBA32F", data=gpu.types.Buffer("FLOAT", pixels.size, pixels)
        )
