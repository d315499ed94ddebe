// gpu_types.h — the one definition of every GPU-visible struct and constant, shared by C++ and
// GLSL so that the two sides cannot drift. C++ sees it inside namespace bvhlab::gpu.
#ifndef BVHLAB_GPU_TYPES_H
#define BVHLAB_GPU_TYPES_H

#ifdef __cplusplus
#include <cstdint>
namespace bvhlab::gpu {
using uint = std::uint32_t;
struct vec3 { float x, y, z; };
struct vec4 { float x, y, z, w; };
#define BVHLAB_CONST inline constexpr
#else
#define BVHLAB_CONST const
#endif

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

#ifdef __cplusplus
static_assert(sizeof(BvhNode) == 32, "BvhNode must stay 32 bytes (std430 layout)");
}  // namespace bvhlab::gpu
#endif
#endif  // BVHLAB_GPU_TYPES_H
