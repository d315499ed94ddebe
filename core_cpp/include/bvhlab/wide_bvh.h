// wide_bvh.h — an 8-wide copy of a built binary tree for fast CPU traversal: one vector test
// checks eight child boxes, and leaves hold triangles four to a packet, tested together (the
// layouts Embree's and tinybvh's CPU kernels use). It is a conversion of the tree, not a rebuild
// (tinybvh's habit): the same boxes, the binary nodes between them collapsed eight children at a
// time, and small subtrees merged into one leaf.
#pragma once
#include <cstdint>

#include "bvhlab/big_vector.h"
#include "bvhlab/bvh.h"
#include "bvhlab/ray.h"

namespace bvhlab {

/// Eight child boxes in structure-of-arrays form, 256 bytes (four cache lines). An unused slot
/// has an inverted box (lo = +inf, hi = -inf), which no ray enters.
struct alignas(64) WideNode {
    float lo_x[8], hi_x[8], lo_y[8], hi_y[8], lo_z[8], hi_z[8];
    std::uint32_t child[8];  ///< inner child: WideNode index; leaf child: its first packet
    std::uint32_t count[8];  ///< 0 for an inner child, else the leaf's packet count
};
static_assert(sizeof(WideNode) == 256);

/// Four primitives of one kind, structure of arrays (160 bytes): v[vertex][axis][lane]. Triangles:
/// the three vertices, as PackedPrim has them (the watertight test reads vertices, so the kernel
/// loads each axis by the ray's axis order). Spheres: centre in v[0], radius in v[1][0]. An empty
/// lane has ref = kNoHit and all vertices 0 (a triangle that is one point is never hit).
struct alignas(32) PrimPacket {
    float v[3][3][4];
    std::uint32_t ref[4];
};
static_assert(sizeof(PrimPacket) == 160);

struct WideBvh {
    BigVector<WideNode> nodes;       ///< root at 0 (also when the whole tree is one leaf); none when empty
    BigVector<PrimPacket> packets;   ///< leaves' primitives, leaf after leaf
    BigVector<std::uint32_t> slots;  ///< per packet lane: its position in Bvh::prims (finish_hit)
};

/// Collapses the binary tree: a subtree of at most four primitives becomes one leaf, and the
/// binary inner nodes that become wide nodes are those of least total surface area (the
/// cost-optimal collapse of Ylitie et al. 2017; each wide node holds up to eight children). A
/// tree that is one leaf gets a root node with that leaf as its only child, so its box is tested
/// as every other traversal tests it.
WideBvh make_wide(const Bvh& bvh);

/// Closest hit through the wide tree (nearest child first, by the middle of the ray's span in
/// each box): the same hit as intersect() on the binary tree, bit for bit, on every instruction
/// set path (isa.h).
Hit intersect_wide(const WideBvh& wide, const Bvh& bvh, const Ray& ray, std::uint32_t* nodes_visited = nullptr);

}  // namespace bvhlab
