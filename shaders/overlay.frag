#version 460
// overlay.frag — line colour in rgb, distance along the primary ray in alpha (report §3.3): the
// trace pass keeps a primary hit only if it is nearer than that distance.
#include "gpu_types.h"
#include "glsl_prelude.glsl"

// A storage buffer, not a uniform one: Mesa 22.3 lavapipe recompiles (and leaks) a shader whose
// branches read uniform-buffer values, at every command buffer execution.
layout(set = 0, binding = BINDING_FRAME, std430) readonly buffer FrameBlock { FrameParams frame; };

#include "tracer/overlay.glsl"

layout(location = 0) in vec3 from_camera;  // the corner relative to the camera (overlay.vert)
layout(location = 1) flat in vec3 line_color;
layout(location = 0) out vec4 color_distance;

void main() {
    float d = overlay_distance(from_camera);
    color_distance = vec4(line_color, d);
    gl_FragDepth = overlay_line_depth(d);  // the lines' own test (overlay.glsl), as the CPU reference's
}
