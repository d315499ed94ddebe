// wide_bvh.h — a 4-wide copy of a built binary tree for fast CPU traversal: one SIMD test checks
// four child boxes (the layout Embree's CPU kernels use). It is a conversion of the tree, not a
// rebuild (tinybvh's habit): same leaves, same primitive order, the binary nodes between them
// collapsed four children at a time.
#pragma once
#include <cstdint>
#include "bvhlab/big_vector.h"
#include "bvhlab/bvh.h"
#include "bvhlab/ray.h"

namespace bvhlab {

/// Four child boxes in structure-of-arrays form, 128 bytes (two cache lines).
struct alignas(64) WideNode {
    float lo_x[4], hi_x[4], lo_y[4], hi_y[4], lo_z[4], hi_z[4];
    std::uint32_t child[4];  ///< inner child: WideNode index; leaf child: first slot in Bvh::prims
    std::uint32_t count[4];  ///< 0 for an inner child, else the leaf's primitive count
};
static_assert(sizeof(WideNode) == 128);

struct WideBvh {
    BigVector<WideNode> nodes;  ///< root at 0 (absent for an empty tree)
    std::uint32_t root_leaf_count = 0;  ///< a tree that is a single leaf has no wide nodes
};

/// Collapses the binary tree: each wide node takes a binary node's children and keeps opening
/// the inner child of largest surface area until it holds four (Wald et al. 2008).
WideBvh make_wide(const Bvh& bvh);

/// Closest hit through the wide tree (nearest child first, boxes tested four at a time).
Hit intersect_wide(const WideBvh& wide, const Bvh& bvh, const Ray& ray, std::uint32_t* nodes_visited = nullptr);

}  // namespace bvhlab
