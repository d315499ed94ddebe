// gpu_types.h — the one definition of every GPU-visible struct, binding number and constant,
// shared by C++ and GLSL so that the two sides cannot drift. C++ sees it in namespace bvhlab::gpu.
// Every struct is made of 16-byte vectors (or a vec3 + a 4-byte scalar), so std430, std140 and
// C++ agree on the layout.
#ifndef BVHLAB_GPU_TYPES_H
#define BVHLAB_GPU_TYPES_H

#ifdef __cplusplus
#include <cstddef>

#include "glsl_compat.h"
namespace bvhlab::gpu {
#define BVHLAB_CONST inline constexpr
#else
#define BVHLAB_CONST const
#endif

// ---- the tree (report §3.1) --------------------------------------------------------------

/// A node of the flattened tree, in depth-first order (report §3.1). 32 bytes.
/// The first child of an internal node is the next node (i + 1); `index` holds the second.
/// A leaf's skip (miss) index is always i + 1, so only internal nodes store theirs: the node
/// visited next when the ray misses this node's box, i.e. the first node after its subtree.
/// One fetch serves a step of the stackless traversal; the stack traversal reads the internal
/// nodes as BvhPair (below) and this format only for the root's box.
struct BvhNode {
    vec3 lo;     ///< box minimum
    uint index;  ///< leaf: first slot in the reference array; internal: second child
    vec3 hi;     ///< box maximum
    uint info;   ///< leaf: primitive count (>= 1); internal: NODE_INTERNAL_BIT | skip index
};

/// An internal node of the same tree with both children's boxes (Aila and Laine, "Understanding the
/// Efficiency of Ray Traversal on GPUs", HPG 2009), 64 bytes: the stack walk tests both children of
/// a node from one fetch of one place, where BvhNode needs two (the first child at i + 1, the
/// second after the first's subtree; siblings share a 64-byte line for a quarter of Sponza's
/// nodes). Pairs are numbered by their node's rank among the internal nodes in depth-first order,
/// so the root is pair 0 and the order is the tree's (make_pair_nodes, render_scene.cpp).
/// A child word: an internal child's pair index, or PAIR_LEAF_BIT | the leaf's first slot in the
/// reference array (Bvh::prims); a count word: the leaf's primitive count, 0 for an internal child.
struct BvhPair {
    vec3 lo_a;  ///< first child's box (the node's i + 1)
    uint child_a;
    vec3 hi_a;
    uint count_a;
    vec3 lo_b;  ///< second child's box (BvhNode::index)
    uint child_b;
    vec3 hi_b;
    uint count_b;
};

/// Marks a leaf in BvhPair's child words, and in the stack walk's entries a leaf child named by
/// its parent and side: PAIR_LEAF_BIT | (2 · pair + side), side 0 for child a (traverse.glsl).
BVHLAB_CONST uint PAIR_LEAF_BIT = 0x80000000u;

/// Set in BvhNode::info for internal nodes; the low 31 bits are then the skip index.
BVHLAB_CONST uint NODE_INTERNAL_BIT = 0x80000000u;
/// A primitive reference carries its kind (report §5.1): this bit set means sphere, else triangle;
/// the low 31 bits index the sphere or triangle array.
BVHLAB_CONST uint REF_SPHERE_BIT = 0x80000000u;
BVHLAB_CONST uint REF_INDEX_MASK = 0x7fffffffu;
/// Deepest tree a traversal stack must hold (report §3.1): height <= MAX_TREE_HEIGHT.
BVHLAB_CONST uint MAX_TREE_HEIGHT = 64u;
/// Every box test of every traversal (CPU and GPU) multiplies the far end of the ray's span in the
/// box, min(exit distance, closest hit so far), by this before comparing it with the entry, and a
/// stacked box is dropped only when its entry lies beyond the closest hit times this: the
/// conservative traversal of Ize, "Robust BVH Ray Traversal" (JCGT 2013). Ize's 1 + 2γ3
/// (γn = nε/(1 - nε), ε = 2^-24) covers the three roundings of a slab distance, (plane - origin) ·
/// (1/dir); we take 1 + 2^-20 (16 ε), room for the last roundings of the triangle test's distance
/// too (geometry.glsl: t = ((u·a + v·b) + w·c) / det · shear), so that a primitive hit at the
/// closest distance so far, lying in a face of its box, is not culled by its box's rounding (the
/// tie rule, closer_hit, needs to see it; the fuzz corpus's found_tie_at_box_entry). It does not
/// cover t's cancellation where a large triangle is hit near the origin (geometry.glsl): there a
/// traversal may still return another primitive than the brute force, within that error.
BVHLAB_CONST float BOX_FAR_SCALE = 1.00000095367431640625f;  // 1 + 2^-20

// ---- the scene as the tracer reads it (report §2.1, §5.1) -------------------------------------

/// A triangle as every ray test reads it, CPU and GPU (48 bytes): its three vertices — the
/// watertight test (geometry.glsl hit_triangle) reads vertices, not edges, so a shared edge is
/// computed from the same numbers in both triangles and no ray slips between them. A zero-area
/// triangle is stored with all three vertices equal to its first: never hit (pack_triangle,
/// core_cpp/include/bvhlab/geometry.h). The CPU traversal keeps spheres in the same layout in its
/// leaf-ordered array: centre in v0, radius in v1.x.
struct GpuTriangle {
    vec3 v0;
    uint material;  ///< index into the materials (the tracer's array; 0 in the CPU traversal's)
    vec3 v1;
    uint ref;  ///< the primitive reference (REF_SPHERE_BIT | index for a sphere)
    vec3 v2;
    uint unused;  ///< 0
};

/// A sphere (32 bytes): centre and radius, material index in material.x.
struct GpuSphere {
    vec4 center_radius;
    uvec4 material;
};

/// A Whitted material (report §2.1, 32 bytes): colour, reflective and transparent factors, IOR.
struct GpuMaterial {
    vec4 color_reflective;  ///< rgb colour, a = reflective factor
    vec4 transparent_ior;   ///< x = transparent factor, y = index of refraction, z = holdout (1: a hole in the
                            ///< image where a camera ray meets it, black where another ray does; Cycles' holdout),
                            ///< w = the RAY_* bits of the rays that pass through it as if it were not there
};

/// An instance of a two-level scene as the tracer reads it (issue 34), 64 bytes, stored in the TLAS's
/// leaf order (a TLAS leaf's slot is its instance's place here). The rows of the world-to-object
/// transform's 3×3 part L, and in w the object's origin in the world P (ObjectMap, transform.h: a
/// world point p goes to L·(p - P)), move a world ray into object space; L's transpose is
/// the inverse transpose of the object-to-world transform, which carries normals back into the world
/// (traverse.glsl instance_ray, surface.glsl surface_at). `tree` places the instance's BLAS in the
/// scene's forest of trees (make_render_scene, render_scene.cpp).
struct GpuInstance {
    vec4 row0;
    vec4 row1;
    vec4 row2;
    uvec4 tree;  ///< x: the BLAS's root node, y: one past its last node, z: its root pair, w: the instance's index
};

/// Hit::instance and Walk::instance of a flat scene, or of the top level of a two-level one.
BVHLAB_CONST uint NO_INSTANCE = 0xffffffffu;

/// One box of the overlay pass (report §3.3), 32 bytes; boxes are stored sorted by depth.
struct GpuBox {
    vec4 lo_depth;  ///< xyz = minimum, w = depth in the tree
    vec4 hi;        ///< xyz = maximum
};

// ---- per-frame parameters (a read-only storage buffer: see trace.comp) -------------------

/// RenderSettings::mode: the Whitted image, or the box tests of the primary rays as colours.
BVHLAB_CONST uint MODE_SHADE = 0u;
BVHLAB_CONST uint MODE_HEATMAP = 1u;
/// Traversal counters of a ray (issue 35; AMD's Radeon Raytracing Analyzer's traversal counters),
/// in this order in the per-pixel sums (DeviceAddresses::accum_counts) and the images
/// (RenderImages::counters); TraversalCounter (render_settings.h) names them. Counted in
/// traverse.glsl for every walk; a pixel keeps those of its primary rays' closest-hit walks.
BVHLAB_CONST uint COUNTER_BOX_TESTS = 0u;      ///< boxes tested (the heatmap's cost)
BVHLAB_CONST uint COUNTER_BOX_HITS = 1u;       ///< ... that the ray entered
BVHLAB_CONST uint COUNTER_PRIM_TESTS = 2u;     ///< primitives tested
BVHLAB_CONST uint COUNTER_PRIM_HITS = 3u;      ///< ... that became the closest hit so far
BVHLAB_CONST uint COUNTER_INSTANCE_HITS = 4u;  ///< two-level: instances entered (TLAS leaves reached)
BVHLAB_CONST uint COUNTER_COUNT = 5u;
/// One walk's traversal counters, or a pixel's sums of them (COUNTER_* order, one field each).
struct TraversalCounts {
    uint box_tests;
    uint box_hits;
    uint prim_tests;
    uint prim_hits;
    uint instance_hits;
};
/// The traversal variant (report §3.1), a specialization constant of trace.comp.
BVHLAB_CONST uint TRAVERSAL_STACK = 0u;
BVHLAB_CONST uint TRAVERSAL_STACKLESS = 1u;
/// The CPU tracer only: each query answered at once by the CPU queries' 8-wide tree
/// (cpu_tracer.h wide_walk); where it cannot answer one, the stack walk does.
BVHLAB_CONST uint TRAVERSAL_WIDE = 2u;

/// Device addresses (buffer_reference_uvec2: low word, high word) of every array the shaders
/// read or write, so no storage-buffer binding limit (128 MiB on lavapipe) caps a scene.
struct DeviceAddresses {
    uvec2 nodes;          ///< BvhNode[node_count]: the stackless walk's, and the stack walk's root
                          ///< (two-level: the TLAS's nodes, then every BLAS's: RenderScene::forest_nodes)
    uvec2 pairs;          ///< BvhPair, one per internal node: the stack walk's
    uvec2 prims;          ///< GpuTriangle, the tree's primitives in leaf order (Bvh::prims; two-level: every BLAS's)
    uvec2 instances;      ///< GpuInstance, two-level scenes only (frame.instance_count of them)
    uvec2 triangles;      ///< GpuTriangle
    uvec2 spheres;        ///< GpuSphere
    uvec2 materials;      ///< GpuMaterial
    uvec2 boxes;          ///< GpuBox, sorted by depth (overlay pass)
    uvec2 accum_color;    ///< vec4 per pixel: sum of sample colours (rgb), sum of box tests (a)
    uvec2 accum_depth;    ///< float per pixel: nearest view-axis depth of a primary ray's hit
    uvec2 accum_samples;  ///< uint per pixel: samples accumulated
    uvec2 slot_state;     ///< uvec4[STATE_WORDS] per slot: a pixel's suspended trace (see state.glsl)
    uvec2 slot_rays;      ///< uvec4[3 × ray_stack_entries] per slot: its Whitted ray stack
    uvec2 slot_nodes;     ///< uvec2[node_stack_entries] per slot: its traversal stack (child, entry t; traverse.glsl)
    uvec2 counters;       ///< uint[2], atomic: slots that ended a dispatch with work left, that failed
    uvec2 accum_counts;   ///< uint[COUNTER_COUNT] per pixel: sums of the traversal counters (frame.count_traversal)
    uvec2 accum_covered;  ///< uint per pixel: samples whose primary ray showed something but a holdout (with
                          ///< film_transparent: a surface or the overlay's line); frame.count_covered: the alpha
};

/// The Whitted tracer's rays (report §2.1), as bits of a material's hidden rays (GpuMaterial.transparent_ior.w:
/// Cycles' Object ▸ Visibility ▸ Ray Visibility, whose Glossy and Transmission are the reflection and the
/// refraction here; the tracer sends no diffuse rays).
BVHLAB_CONST uint RAY_CAMERA = 1u;
BVHLAB_CONST uint RAY_SHADOW = 2u;
BVHLAB_CONST uint RAY_REFLECTION = 4u;
BVHLAB_CONST uint RAY_REFRACTION = 8u;
BVHLAB_CONST uint RAY_KINDS = 15u;  ///< every bit

/// FrameParams::projection (camera.h Projection, in its order).
BVHLAB_CONST uint PROJECTION_PERSPECTIVE = 0u;
BVHLAB_CONST uint PROJECTION_ORTHOGRAPHIC = 1u;
BVHLAB_CONST uint PROJECTION_EQUIRECTANGULAR = 2u;
BVHLAB_CONST uint PROJECTION_FISHEYE_EQUIDISTANT = 3u;

/// Everything a frame reads, field by field (std430 and C++ agree: each vec3 is followed by a
/// 4-byte scalar, then come vec4s, 4-byte scalars, then the addresses, 8-aligned).
/// The camera (camera.h; make_camera_frame in core_cpp/src/render/camera.cpp): a pixel's sample
/// at image position q (pixels from the top-left corner) has screen coordinates
/// screen.xy + q · screen.zw, which the projection turns into a ray (camera_ray, camera.glsl):
/// perspective: the direction forward + x·right + y·up; orthographic: the origin position +
/// x·right + y·up; panoramic: Cycles' view-plane coordinates (u, v) in [0, 1]² (v up).
struct FrameParams {
    vec3 camera_position;
    uint projection;        ///< PROJECTION_*
    vec3 camera_forward;    ///< unit; the view axis
    float clip_start;       ///< primary rays see what lies this far along the view axis (panoramic: from
                            ///< the position) and no nearer
    vec3 camera_right;      ///< unit, orthogonal to forward
    float clip_end;         ///< ... and no farther (may be +inf)
    vec3 camera_up;         ///< unit, orthogonal to forward and right
    float aperture_radius;  ///< thin lens radius (world units); 0: a pinhole
    vec4 screen;            ///< xy: screen coordinates of the image's top-left corner; zw: per pixel
    vec4 panorama;          ///< equirectangular: Cycles' equirectangular_range (longitude span, -longitude
                            ///< min, latitude span, π/2 - latitude min; radians); fisheye: x = field of view
    vec4 overlay_color;     ///< rgb: the overlay's lines when not coloured by depth (w unused)
    vec3 light_position;
    uint count_covered;   ///< 1: addr.accum_covered counts each pixel's covered samples, its alpha (film_transparent,
                          ///< or a scene with a holdout material: its camera rays' samples are uncovered)
    vec3 light_color;     ///< rgb, already multiplied by the intensity
    float heatmap_scale;  ///< box tests per primary ray shown as full red (MODE_HEATMAP)
    vec3 sky;             ///< rgb: the atmosphere colour of rays that hit nothing (report §2.1)
    float overlay_near;   ///< overlay pass: distance of the near clipping plane
    uint width;           ///< image size in pixels
    uint height;
    uint samples_per_axis;        ///< n: n×n samples per pixel on a regular grid
    uint max_ray_depth;           ///< bounces of reflection and refraction (0 = primary rays only)
    uint mode;                    ///< MODE_SHADE or MODE_HEATMAP
    uint node_count;              ///< of the tree (the stackless traversal stops there); two-level: of the TLAS
    uint overlay_enabled;         ///< 1: the trace pass reads the overlay pass's lines
    uint overlay_color_by_depth;  ///< 1: line colour by tree depth (depth_color), else overlay_color
    float overlay_far;            ///< overlay pass: distance of the far clipping plane
    uint overlay_first_box;       ///< the boxes drawn: [overlay_first_box, overlay_last_box) (report §3.3.1)
    uint overlay_last_box;
    uint sample_target;       ///< this pass traces each pixel's samples up to (not including) this index
    uint steps_per_dispatch;  ///< trace_steps() iterations one invocation may run in one dispatch
    uint stamp;               ///< tells a slot's state from an earlier tile's or pass's (never 0)
    uint ray_stack_entries;   ///< per slot: max_ray_depth + 1
    uint node_stack_entries;  ///< per slot: tree height - 1 (at least 1)
    uint tile_x;              ///< the tile of this dispatch: first pixel, size; slot = local y · width + x
    uint tile_y;
    uint tile_width;
    uint tile_height;
    uint max_work_per_pixel;   ///< a trace with more steps of work in a pass fails (0xffffffff: no cap)
    float focus_distance;      ///< the thin lens's focus, along the view axis
    uint instance_count;       ///< two-level scenes: instances in the TLAS (0: a flat scene, one level)
    uint count_traversal;      ///< 1: the trace pass sums the traversal counters into addr.accum_counts
    uint film_transparent;     ///< 1: a camera ray that shows nothing adds no colour and does not cover the
                               ///< pixel (RenderSettings::film_transparent; count_covered says it is counted)
    float overlay_line_width;  ///< whole pixels across the overlay's lines (RenderSettings::line_width rounded,
                               ///< as the rasterizers draw it): whether the trace pass's query stops at the line
                               ///< (query_stops_at_line: one pixel wide)
    uint hidden_materials;     ///< 1: a material hides from some rays (GpuMaterial.transparent_ior.w): the walks
                               ///< look at each hit's material (0: every surface is seen by every ray)
    uint reserved;             ///< unused (keeps `addr` on 8 bytes, as GLSL's std430 puts it)
    DeviceAddresses addr;
};

// ---- bindings, workgroups, limits ------------------------------------------------------

BVHLAB_CONST uint BINDING_FRAME = 0u;    ///< FrameParams, read-only storage buffer (trace and overlay)
BVHLAB_CONST uint BINDING_OVERLAY = 1u;  ///< rgba32f storage image: the overlay pass's line points (trace reads)
BVHLAB_CONST uint TRACE_GROUP_X = 8u;    ///< trace.comp's workgroup: 8×8 pixels of a tile
BVHLAB_CONST uint TRACE_GROUP_Y = 8u;
/// Entries of the Whitted ray stack: each bounce pops one ray and pushes at most two, so at most
/// max_ray_depth + 1 wait at once.
BVHLAB_CONST uint RAY_STACK_SIZE = 16u;
BVHLAB_CONST uint MAX_RAY_DEPTH = 15u;  ///< bounces; keeps the ray stack within RAY_STACK_SIZE
BVHLAB_CONST uint MAX_SAMPLES_PER_AXIS = 16u;
/// Loop iterations one shader invocation may run in one dispatch (trace_steps' budget). Mesa's
/// llvmpipe (lavapipe) ends every loop of an invocation once they have run
/// LP_MAX_TGSI_LOOP_ITERATIONS = 65535 iterations together (gallivm/lp_bld_limits.h: one counter
/// for all loops of the shader, taken once per iteration of the SIMD vector, also for a loop that
/// no lane enters); trace_steps counts every iteration of its loops as the SIMD vector runs them
/// (shade.glsl); trace.comp has no other loop, and the margin covers trace_steps' last few steps
/// (it may end a few steps past its budget). Real
/// GPUs have a watchdog instead: the host also shortens the budget to keep each dispatch brief
/// (vk_trace_job.cpp).
BVHLAB_CONST uint MAX_STEPS_PER_DISPATCH = 60000u;
/// The least budget: enough for a step of work after the loops' own counting (no livelock).
BVHLAB_CONST uint MIN_STEPS_PER_DISPATCH = 16u;
/// FrameParams::max_work_per_pixel meaning "no cap".
BVHLAB_CONST uint NO_WORK_CAP = 0xffffffffu;
/// Words (uvec4) of a slot's saved trace state (state.glsl).
BVHLAB_CONST uint STATE_WORDS = 15u;
BVHLAB_CONST uint NO_HIT = 0xffffffffu;
BVHLAB_CONST uint NODE_SKIP_MASK = 0x7fffffffu;
BVHLAB_CONST float FAR_AWAY = 3.0e38f;  ///< tmax of a ray that may go anywhere

// ---- shading constants (report §2.1) ---------------------------------------------------------
BVHLAB_CONST float AMBIENT = 0.1f;     ///< light every opaque surface gets, lit or not
BVHLAB_CONST float SPECULAR = 0.25f;   ///< Blinn-Phong highlight strength
BVHLAB_CONST float SHININESS = 48.0f;  ///< Blinn-Phong exponent
/// Overlay line colour when lines are not coloured by depth (report §3.3).

#ifdef __cplusplus
static_assert(sizeof(BvhNode) == 32, "BvhNode must stay 32 bytes (std430 layout)");
static_assert(sizeof(BvhPair) == 64, "BvhPair must stay 64 bytes (std430 layout)");
static_assert(sizeof(GpuTriangle) == 48 && sizeof(GpuSphere) == 32 && sizeof(GpuMaterial) == 32);
static_assert(sizeof(TraversalCounts) == COUNTER_COUNT * 4);
static_assert(sizeof(GpuBox) == 32 && sizeof(GpuInstance) == 64 && sizeof(DeviceAddresses) == 17 * 8);
static_assert(offsetof(FrameParams, width) == 160 && offsetof(FrameParams, addr) == 272);
static_assert(sizeof(FrameParams) == 272 + sizeof(DeviceAddresses));
}  // namespace bvhlab::gpu
#endif
#endif  // BVHLAB_GPU_TYPES_H
