#version 460
// trace.comp — the trace pass (report §3.2, Figure 2): one invocation per pixel of a tile runs the
// shared Whitted tracer (tracer/*.glsl) for at most frame.steps_per_dispatch steps, then saves
// where it stands in its slot; the host dispatches again until every pixel of the tile has traced
// its samples of the pass (issue 8: no dispatch holds unbounded work). The scene, the per-pixel
// sums and the slots are read through buffer device addresses, so no binding limit (128 MiB on
// lavapipe) caps their size. The overlay pass's lines (each pixel's line point and box depth) come in the storage image.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#extension GL_KHR_shader_subgroup_arithmetic : require

#include "gpu_types.h"
#include "glsl_prelude.glsl"

/// TRAVERSAL_STACK or TRAVERSAL_STACKLESS (report §3.1).
layout(constant_id = 0) const uint TRAVERSAL = TRAVERSAL_STACK;
/// Every traversal counter is counted (traverse.glsl); a few ALU operations a step on a GPU.
const bool COUNT_TRAVERSAL = true;
layout(local_size_x = TRACE_GROUP_X, local_size_y = TRACE_GROUP_Y) in;

// A storage buffer, not a uniform one: Mesa 22.3 lavapipe recompiles (and leaks) a shader whose
// branches read uniform-buffer values, at every command buffer execution.
layout(set = 0, binding = BINDING_FRAME, std430) readonly buffer FrameBlock { FrameParams frame; };
layout(set = 0, binding = BINDING_OVERLAY, rgba32f) readonly uniform image2D overlay;

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer NodeArray { BvhNode v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer PairArray { BvhPair v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer TriangleArray { GpuTriangle v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer SphereArray { GpuSphere v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer MaterialArray { GpuMaterial v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer InstanceArray { GpuInstance v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Vec4Array { vec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer FloatArray { float v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer UintArray { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Uvec4Array { uvec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) buffer Uvec2Array { uvec2 v[]; };

BvhNode load_node(uint i) { return NodeArray(frame.addr.nodes).v[i]; }
BvhPair load_pair(uint i) { return PairArray(frame.addr.pairs).v[i]; }
GpuTriangle load_leaf_prim(uint i) { return TriangleArray(frame.addr.prims).v[i]; }
GpuTriangle load_triangle(uint i) { return TriangleArray(frame.addr.triangles).v[i]; }
GpuSphere load_sphere(uint i) { return SphereArray(frame.addr.spheres).v[i]; }
GpuMaterial load_material(uint i) { return MaterialArray(frame.addr.materials).v[i]; }
GpuInstance load_instance(uint i) { return InstanceArray(frame.addr.instances).v[i]; }
uint node_count() { return frame.node_count; }
bool two_level() { return frame.instance_count != 0u; }
vec4 overlay_at(uvec2 p) { return frame.overlay_enabled != 0u ? imageLoad(overlay, ivec2(p)) : vec4(0.0f); }

// The step count of the lanes of a SIMD vector (a subgroup on lavapipe) after a loop: the largest.
uint sync_steps(uint steps) { return subgroupMax(steps); }

// The pixel's sums live in private memory during a dispatch (copied in at the start, out at the
// end); the stacks stay in the slot: dynamically indexed private arrays are slower on lavapipe.
vec4 g_sum;        // colour (rgb) and box tests (a) of the samples so far
float g_depth;     // nearest primary hit
uint g_samples;
uint g_covered;  // samples whose camera ray showed something but a holdout (frame.count_covered)
TraversalCounts g_counts;  // traversal counters of the samples so far (frame.count_traversal)
uint g_slot;
uvec4 state_load(uint k) { return Uvec4Array(frame.addr.slot_state).v[g_slot * STATE_WORDS + k]; }
void state_store(uint k, uvec4 w) { Uvec4Array(frame.addr.slot_state).v[g_slot * STATE_WORDS + k] = w; }
uvec4 ray_word_load(uint k) { return Uvec4Array(frame.addr.slot_rays).v[g_slot * 3u * frame.ray_stack_entries + k]; }
void ray_word_store(uint k, uvec4 w) { Uvec4Array(frame.addr.slot_rays).v[g_slot * 3u * frame.ray_stack_entries + k] = w; }
uvec2 node_stack_load(uint k) { return Uvec2Array(frame.addr.slot_nodes).v[g_slot * frame.node_stack_entries + k]; }
void node_stack_store(uint k, uvec2 e) { Uvec2Array(frame.addr.slot_nodes).v[g_slot * frame.node_stack_entries + k] = e; }
uint samples_done(uvec2 p) { return g_samples; }
void accumulate_sample(uvec2 p, vec3 color, TraversalCounts counts, float depth, bool covered) {
    g_sum = g_sum + vec4(color, float(counts.box_tests));  // in sample order, as the CPU reference adds them
    g_depth = min(g_depth, depth);
    g_samples = g_samples + 1u;
    g_covered = g_covered + (covered ? 1u : 0u);
    g_counts.box_tests += counts.box_tests;
    g_counts.box_hits += counts.box_hits;
    g_counts.prim_tests += counts.prim_tests;
    g_counts.prim_hits += counts.prim_hits;
    g_counts.instance_hits += counts.instance_hits;
}

uint pixel_index(uvec2 p) { return p.y * frame.width + p.x; }

void load_sums(uvec2 p) {
    uint i = pixel_index(p);
    g_counts = TraversalCounts(0u, 0u, 0u, 0u, 0u);
    g_sum = Vec4Array(frame.addr.accum_color).v[i];
    g_depth = FloatArray(frame.addr.accum_depth).v[i];
    g_samples = UintArray(frame.addr.accum_samples).v[i];
    g_covered = 0u;  // a branch, not a select: no load from the null address of a render without alpha
    if (frame.count_covered != 0u) g_covered = UintArray(frame.addr.accum_covered).v[i];
    if (frame.count_traversal == 0u) return;
    UintArray c = UintArray(frame.addr.accum_counts);
    uint k = i * COUNTER_COUNT;
    g_counts = TraversalCounts(c.v[k + COUNTER_BOX_TESTS], c.v[k + COUNTER_BOX_HITS], c.v[k + COUNTER_PRIM_TESTS],
                               c.v[k + COUNTER_PRIM_HITS], c.v[k + COUNTER_INSTANCE_HITS]);
}

void store_sums(uvec2 p) {
    uint i = pixel_index(p);
    Vec4Array(frame.addr.accum_color).v[i] = g_sum;
    FloatArray(frame.addr.accum_depth).v[i] = g_depth;
    UintArray(frame.addr.accum_samples).v[i] = g_samples;
    if (frame.count_covered != 0u) UintArray(frame.addr.accum_covered).v[i] = g_covered;
    if (frame.count_traversal == 0u) return;
    UintArray c = UintArray(frame.addr.accum_counts);
    uint k = i * COUNTER_COUNT;
    c.v[k + COUNTER_BOX_TESTS] = g_counts.box_tests;
    c.v[k + COUNTER_BOX_HITS] = g_counts.box_hits;
    c.v[k + COUNTER_PRIM_TESTS] = g_counts.prim_tests;
    c.v[k + COUNTER_PRIM_HITS] = g_counts.prim_hits;
    c.v[k + COUNTER_INSTANCE_HITS] = g_counts.instance_hits;
}

#include "tracer/geometry.glsl"
#include "tracer/shade_colors.glsl"
#include "tracer/overlay.glsl"
#include "tracer/traverse.glsl"
#include "tracer/shade.glsl"
#include "tracer/state.glsl"

layout(buffer_reference, std430, buffer_reference_align = 4) buffer Counters { uint unfinished; uint failed; };

void main() {
    uvec2 local = gl_GlobalInvocationID.xy;
    if (local.x >= frame.tile_width || local.y >= frame.tile_height) return;
    uvec2 p = uvec2(frame.tile_x, frame.tile_y) + local;
    g_slot = local.y * frame.tile_width + local.x;
    if (slot_done(frame.stamp)) return;
    bool resumed = slot_stamp() == frame.stamp;
    load_sums(p);
    TraceState s = resumed ? load_state() : begin_pixel(p, g_samples, frame.sample_target);
    trace_steps(s, frame.steps_per_dispatch);
    store_sums(p);
    if (s.phase >= PHASE_DONE) {
        save_done(s, frame.stamp);
        if (s.phase == PHASE_FAILED) atomicAdd(Counters(frame.addr.counters).failed, 1u);
        return;
    }
    save_state(s, frame.stamp);
    atomicAdd(Counters(frame.addr.counters).unfinished, 1u);
}
