#version 460
// overlay.frag — the line's point relative to the camera in xyz (interpolated at the fragment: the
// point of the segment it was drawn for, up to half the line's width off the fragment's centre),
// its box's depth + 1 in w (report §3.3): the trace pass keeps a primary hit only if it is nearer
// than the line's distance, or the line lies on it (line_on_surface in shade.glsl).
#include "gpu_types.h"
#include "glsl_prelude.glsl"

// A storage buffer, not a uniform one: Mesa 22.3 lavapipe recompiles (and leaks) a shader whose
// branches read uniform-buffer values, at every command buffer execution.
layout(set = 0, binding = BINDING_FRAME, std430) readonly buffer FrameBlock { FrameParams frame; };

#include "tracer/overlay.glsl"

layout(location = 0) in vec3 from_camera;  // the corner relative to the camera (overlay.vert)
layout(location = 1) flat in uint box_depth;
layout(location = 0) out vec4 line_point;

void main() {
    float d = overlay_distance(from_camera);
    line_point = vec4(from_camera, float(box_depth + 1u));
    gl_FragDepth = overlay_line_depth(d);  // the lines' own test (overlay.glsl), as the CPU reference's
}
