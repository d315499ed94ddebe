#version 460
// trace.comp — the trace pass (report §3.2, Figure 2): one invocation per pixel runs the shared
// Whitted tracer (tracer/*.glsl) over the scene, read through buffer device addresses so no
// binding limit (128 MiB on lavapipe) caps the scene size. The image holds the overlay pass's
// lines (rgb + distance) on entry and the final colour on exit.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

#include "gpu_types.h"
#include "glsl_prelude.glsl"

/// TRAVERSAL_STACK or TRAVERSAL_STACKLESS (report §3.1).
layout(constant_id = 0) const uint TRAVERSAL = TRAVERSAL_STACK;
layout(local_size_x = 8, local_size_y = 8) in;  // = TRACE_GROUP_X, TRACE_GROUP_Y

// A storage buffer, not a uniform one: Mesa 22.3 lavapipe recompiles (and leaks) a shader whose
// branches read uniform-buffer values, at every command buffer execution.
layout(set = 0, binding = BINDING_FRAME, std430) readonly buffer FrameBlock { FrameParams frame; };
layout(set = 0, binding = BINDING_IMAGE, rgba32f) uniform image2D image;

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer NodeArray { BvhNode v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer RefArray { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer TriangleArray { GpuTriangle v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer SphereArray { GpuSphere v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer MaterialArray { GpuMaterial v[]; };

BvhNode load_node(uint i) { return NodeArray(frame.addr_nodes_refs.xy).v[i]; }
uint load_ref(uint i) { return RefArray(frame.addr_nodes_refs.zw).v[i]; }
GpuTriangle load_triangle(uint i) { return TriangleArray(frame.addr_triangles_spheres.xy).v[i]; }
GpuSphere load_sphere(uint i) { return SphereArray(frame.addr_triangles_spheres.zw).v[i]; }
GpuMaterial load_material(uint i) { return MaterialArray(frame.addr_materials_boxes.xy).v[i]; }
uint node_count() { return frame.flags.z; }
vec4 overlay_at(uvec2 p) { return imageLoad(image, ivec2(p)); }

#include "tracer/geometry.glsl"
#include "tracer/traverse.glsl"
#include "tracer/shade_colors.glsl"
#include "tracer/shade.glsl"

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= frame.size.x || p.y >= frame.size.y) return;
    imageStore(image, ivec2(p), trace_pixel(p));
}
