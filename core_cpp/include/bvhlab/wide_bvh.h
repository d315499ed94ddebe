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

/// Four primitives of one kind, structure of arrays (160 bytes). Triangles: first vertex and the
/// two edges from it, as PackedPrim has them (Möller–Trumbore). Spheres: centre in v0, radius in
/// e1x. An empty lane has ref = kNoHit and zero edges (a triangle with zero edges is never hit).
struct alignas(32) PrimPacket {
    float v0x[4], v0y[4], v0z[4], e1x[4], e1y[4], e1z[4], e2x[4], e2y[4], e2z[4];
    std::uint32_t ref[4];
};
static_assert(sizeof(PrimPacket) == 160);

struct WideBvh {
    BigVector<WideNode> nodes;            ///< root at 0 (absent when the whole tree is one leaf)
    BigVector<PrimPacket> packets;        ///< leaves' primitives, leaf after leaf
    BigVector<std::uint32_t> slots;       ///< per packet lane: its position in Bvh::prims (finish_hit)
    std::uint32_t root_packets = 0;       ///< a tree that is one leaf: its packet count, no nodes
};

/// Collapses the binary tree: each wide node takes a binary node's children and keeps opening
/// the inner child of largest surface area until it holds eight (Wald et al. 2008); a subtree of
/// at most four primitives becomes one leaf.
WideBvh make_wide(const Bvh& bvh);

/// Closest hit through the wide tree (nearest child first): the same hit as intersect() on the
/// binary tree, bit for bit, on every instruction set path (isa.h).
Hit intersect_wide(const WideBvh& wide, const Bvh& bvh, const Ray& ray, std::uint32_t* nodes_visited = nullptr);

}  // namespace bvhlab
