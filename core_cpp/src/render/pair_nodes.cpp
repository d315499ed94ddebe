// The stack walk's node format: each internal node of the depth-first tree with its two children's
// boxes, so one 64-byte fetch serves a node's two box tests (Aila and Laine, HPG 2009).
#include "bvhlab/pair_nodes.h"

namespace bvhlab {
namespace {

/// A child's words: its pair index (`rank`, internal) or PAIR_LEAF_BIT | first slot and count.
void set_child(const BvhNode& child, std::uint32_t rank, gpu::vec3& lo, gpu::vec3& hi, std::uint32_t& word,
               std::uint32_t& count) {
    lo = child.lo;
    hi = child.hi;
    word = is_leaf(child) ? gpu::PAIR_LEAF_BIT | child.index : rank;
    count = is_leaf(child) ? leaf_count(child) : 0;
}

}  // namespace

BigVector<gpu::BvhPair> make_pair_nodes(const Bvh& bvh) {
    const std::uint32_t n = bvh.node_count();
    // rank[i]: internal nodes before node i in depth-first order (node i's pair, if internal)
    BigVector<std::uint32_t> rank(n);
    std::uint32_t internal = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
        rank[i] = internal;
        internal += is_leaf(bvh.nodes[i]) ? 0 : 1;
    }
    BigVector<gpu::BvhPair> pairs(internal);
    for (std::uint32_t i = 0; i < n; ++i) {
        const BvhNode& node = bvh.nodes[i];
        if (is_leaf(node)) continue;
        gpu::BvhPair& p = pairs[rank[i]];
        const std::uint32_t a = i + 1, b = node.index;
        set_child(bvh.nodes[a], rank[a], p.lo_a, p.hi_a, p.child_a, p.count_a);
        set_child(bvh.nodes[b], rank[b], p.lo_b, p.hi_b, p.child_b, p.count_b);
    }
    return pairs;
}

}  // namespace bvhlab
