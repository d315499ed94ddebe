"""The box-edge shader: one instance per box, 24 vertices (12 edges) per instance.

The Python `gpu` API has no per-instance vertex attributes, so the boxes live in an RGBA32F
texture, two texels per box (min.xyz + depth, max.xyz + a measure's value), fetched by instance index, counted back
from the last box of the range (deepest first, see BoxBatch.draw). The colour of each depth comes
from a palette texture filled from the core (`bvhlab._core.depth_colors`), a measure's from the
core's heat ramp (`bvhlab._core.heat_colors`) in another.
"""

from __future__ import annotations

_VERTEX = """
void main()
{
  int texel = 2 * (last_box - gl_InstanceID);
  int width = textureSize(boxes, 0).x;  /* even, so both texels of a box share a row */
  vec4 lo = texelFetch(boxes, ivec2(texel % width, texel / width), 0);
  vec4 hi = texelFetch(boxes, ivec2(texel % width + 1, texel / width), 0);
  gl_Position = view_projection * vec4(mix(lo.xyz, hi.xyz, corner), 1.0);
  if (color_mode == 2) { /* a measure: the box's value on the heat ramp */
    int entry = clamp(int(hi.w * float(textureSize(heat, 0).x - 1) + 0.5), 0, textureSize(heat, 0).x - 1);
    edge_color = vec4(texelFetch(heat, ivec2(entry, 0), 0).rgb, uniform_color.a);
  }
  else if (color_mode == 1) {
    edge_color = vec4(texelFetch(palette, ivec2(int(lo.w), 0), 0).rgb, uniform_color.a);
  }
  else {
    edge_color = uniform_color;
  }
}
"""

_FRAGMENT = """
void main()
{
  frag_color = edge_color;
}
"""

_shader = None


def box_shader():
    """The compiled shader (compiled once per session; needs a GPU context)."""
    global _shader
    if _shader is None:
        import gpu

        interface = gpu.types.GPUStageInterfaceInfo("bvhlab_box_interface")
        interface.flat("VEC4", "edge_color")
        info = gpu.types.GPUShaderCreateInfo()
        info.vertex_in(0, "VEC3", "corner")
        info.vertex_out(interface)
        info.sampler(0, "FLOAT_2D", "boxes")
        info.sampler(1, "FLOAT_2D", "palette")
        info.sampler(2, "FLOAT_2D", "heat")
        info.push_constant("MAT4", "view_projection")
        info.push_constant("VEC4", "uniform_color")
        info.push_constant("INT", "last_box")
        info.push_constant("INT", "color_mode")
        info.fragment_out(0, "VEC4", "frag_color")
        info.vertex_source(_VERTEX)
        info.fragment_source(_FRAGMENT)
        _shader = gpu.shader.create_from_info(info)
    return _shader


def forget_shader() -> None:
    global _shader
    _shader = None
