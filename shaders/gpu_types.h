// gpu_types.h — the one definition of every GPU-visible struct, binding number and constant,
// shared by C++ and GLSL so that the two sides cannot drift. C++ sees it in namespace bvhlab::gpu.
// Every struct is made of 16-byte vectors (or a vec3 + a 4-byte scalar), so std430, std140 and
// C++ agree on the layout.
#ifndef BVHLAB_GPU_TYPES_H
#define BVHLAB_GPU_TYPES_H

#ifdef __cplusplus
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
/// One fetch therefore serves both the stack traversal and the stackless one.
struct BvhNode {
    vec3 lo;     ///< box minimum
    uint index;  ///< leaf: first slot in the reference array; internal: second child
    vec3 hi;     ///< box maximum
    uint info;   ///< leaf: primitive count (>= 1); internal: NODE_INTERNAL_BIT | skip index
};

/// Set in BvhNode::info for internal nodes; the low 31 bits are then the skip index.
BVHLAB_CONST uint NODE_INTERNAL_BIT = 0x80000000u;
/// A primitive reference carries its kind (report §5.1): this bit set means sphere, else triangle;
/// the low 31 bits index the sphere or triangle array.
BVHLAB_CONST uint REF_SPHERE_BIT = 0x80000000u;
BVHLAB_CONST uint REF_INDEX_MASK = 0x7fffffffu;
/// Deepest tree a traversal stack must hold (report §3.1): height <= MAX_TREE_HEIGHT.
BVHLAB_CONST uint MAX_TREE_HEIGHT = 64u;

// ---- the scene as the tracer reads it (report §2.1, §5.1) -------------------------------------

/// A triangle (48 bytes): first vertex, the two edges from it (Möller–Trumbore needs no more),
/// and its material index as the bits of v0.w. A zero-area triangle has zero edges: never hit.
struct GpuTriangle {
    vec4 v0;
    vec4 e1;
    vec4 e2;
};

/// A sphere (32 bytes): centre and radius, material index in material.x.
struct GpuSphere {
    vec4 center_radius;
    uvec4 material;
};

/// A Whitted material (report §2.1, 32 bytes): colour, reflective and transparent factors, IOR.
struct GpuMaterial {
    vec4 color_reflective;  ///< rgb colour, a = reflective factor
    vec4 transparent_ior;   ///< x = transparent factor, y = index of refraction
};

/// One box of the overlay pass (report §3.3), 32 bytes; boxes are stored sorted by depth.
struct GpuBox {
    vec4 lo_depth;  ///< xyz = minimum, w = depth in the tree
    vec4 hi;        ///< xyz = maximum
};

// ---- per-frame parameters (a read-only storage buffer: see trace.comp) -------------------

BVHLAB_CONST uint MODE_SHADE = 0u;
BVHLAB_CONST uint MODE_HEATMAP = 1u;
BVHLAB_CONST uint TRAVERSAL_STACK = 0u;
BVHLAB_CONST uint TRAVERSAL_STACKLESS = 1u;

struct FrameParams {
    vec4 camera_position;  ///< xyz; w = tan(vertical field of view / 2)
    vec4 camera_forward;   ///< xyz (unit); w = aspect ratio, width / height
    vec4 camera_right;     ///< xyz (unit)
    vec4 camera_up;        ///< xyz (unit, orthogonal to forward and right)
    vec4 light_position;   ///< xyz
    vec4 light_color;      ///< rgb, already multiplied by the intensity
    vec4 sky;              ///< rgb: the atmosphere colour of rays that hit nothing
    uvec4 size;            ///< width, height, samples per pixel axis (n×n), max ray depth
    uvec4 flags;           ///< mode, overlay present (0/1), node count, heatmap full scale (box tests)
    vec4 scale;            ///< x = ray offset epsilon, y = overlay near plane, z = overlay far plane
    uvec4 addr_nodes_refs;        ///< device addresses (lo, hi words) of the nodes and the references
    uvec4 addr_triangles_spheres; ///< ... of the triangles and the spheres
    uvec4 addr_materials_boxes;   ///< ... of the materials and the overlay boxes
    uvec4 overlay_range;          ///< first box, box count, line colour by depth (0/1), unused
};

// ---- bindings and workgroups -------------------------------------------------------------

BVHLAB_CONST uint BINDING_FRAME = 0u;   ///< FrameParams, read-only storage buffer (trace and overlay)
BVHLAB_CONST uint BINDING_IMAGE = 1u;   ///< rgba32f storage image: overlay in, colour out (trace)
BVHLAB_CONST uint TRACE_GROUP_X = 8u;
BVHLAB_CONST uint TRACE_GROUP_Y = 8u;
/// Entries of the Whitted ray stack: each bounce pops one ray and pushes at most two.
BVHLAB_CONST uint RAY_STACK_SIZE = 32u;
BVHLAB_CONST uint MAX_RAY_DEPTH = 15u;   ///< keeps the ray stack within RAY_STACK_SIZE
BVHLAB_CONST uint MAX_SAMPLES_PER_AXIS = 16u;
BVHLAB_CONST uint NO_HIT = 0xffffffffu;
BVHLAB_CONST uint NODE_SKIP_MASK = 0x7fffffffu;
BVHLAB_CONST float FAR_AWAY = 3.0e38f;       ///< tmax of a ray that may go anywhere

// ---- shading constants (report §2.1) ---------------------------------------------------------
BVHLAB_CONST float AMBIENT = 0.1f;     ///< light every opaque surface gets, lit or not
BVHLAB_CONST float SPECULAR = 0.25f;   ///< Blinn-Phong highlight strength
BVHLAB_CONST float SHININESS = 48.0f;  ///< Blinn-Phong exponent

#ifdef __cplusplus
static_assert(sizeof(BvhNode) == 32, "BvhNode must stay 32 bytes (std430 layout)");
static_assert(sizeof(GpuTriangle) == 48 && sizeof(GpuSphere) == 32 && sizeof(GpuMaterial) == 32);
static_assert(sizeof(GpuBox) == 32 && sizeof(FrameParams) == 14 * 16);
}  // namespace bvhlab::gpu
#endif
#endif  // BVHLAB_GPU_TYPES_H
