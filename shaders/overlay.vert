#version 460
// overlay.vert — the BVH overlay pass (report §3.3): instanced LINE_LIST, 24 vertices per box
// (its 12 edges); instance i is box first_box + i of the depth-sorted box array, so a depth range
// is one offset and one count (§3.3.1).
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

#include "gpu_types.h"
#include "glsl_prelude.glsl"

// A storage buffer, not a uniform one: Mesa 22.3 lavapipe recompiles (and leaks) a shader whose
// branches read uniform-buffer values, at every command buffer execution.
layout(set = 0, binding = BINDING_FRAME, std430) readonly buffer FrameBlock { FrameParams frame; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer BoxArray { GpuBox v[]; };

#include "tracer/overlay.glsl"

// The corner relative to the camera, interpolated as the CPU reference's rasterizer interpolates
// it (overlay_cpu.cpp): a world position interpolated and then made relative in the fragment
// shader rounded at the scene's magnitude, and 7-15% of whitted's line pixels 1e3-1e5 from the
// origin took another box's colour than the CPU's (a helper's audit).
layout(location = 0) out vec3 from_camera;
// The box's depth in the tree: the trace pass colours the line (line_color in shade.glsl).
layout(location = 1) flat out uint box_depth;

void main() {
    GpuBox box = BoxArray(frame.addr.boxes).v[gl_InstanceIndex];
    uint depth = uint(box.lo_depth.w);
    vec3 corner = corner_position(box.lo_depth.xyz, box.hi.xyz, box_corner(uint(gl_VertexIndex)));
    from_camera = corner - frame.camera_position;
    box_depth = depth;
    gl_Position = overlay_clip(corner);
}
