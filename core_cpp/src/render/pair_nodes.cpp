// The stack walk's node format: each internal node of the depth-first tree with its two children's
// boxes, so one 64-byte fetch serves a node's two box tests (Aila and Laine, HPG 2009).
#include "bvhlab/pair_nodes.h"

#include <stdexcept>
#include <vector>

namespace bvhlab {
namespace {

/// A child's words: its pair index (`rank`, internal) or PAIR_LEAF_BIT | first slot and count.
void set_child(const BvhNode& child, std::uint32_t rank, gpu::vec3& lo, gpu::vec3& hi, std::uint32_t& word,
               std::uint32_t& count) {
    if (is_leaf(child) && (child.index & gpu::PAIR_LEAF_BIT) != 0)
        throw std::invalid_argument("make_pair_nodes: a leaf's first slot does not fit in 31 bits");
    lo = child.lo;
    hi = child.hi;
    word = is_leaf(child) ? gpu::PAIR_LEAF_BIT | child.index : rank;
    count = is_leaf(child) ? leaf_count(child) : 0;
}

[[noreturn]] void not_a_tree() {
    throw std::invalid_argument("make_pair_nodes: the nodes are not a depth-first binary tree");
}

/// An internal node whose second child is still to come in the depth-first order.
struct Pending {
    std::uint32_t pair;          ///< its rank among the internal nodes
    std::uint32_t second_child;  ///< BvhNode::index
};

}  // namespace

BigVector<gpu::BvhPair> make_pair_nodes(const Bvh& bvh) {
    // One pass in depth-first order, reading the nodes once in sequence: node i is the first child
    // of node i - 1 where that is internal, else the second child of the nearest internal node whose
    // second child has not come yet (the top of `pending`). A full binary tree of n nodes has
    // (n - 1) / 2 internal ones.
    const std::uint32_t n = bvh.node_count();
    BigVector<gpu::BvhPair> pairs(n / 2);
    std::vector<Pending> pending;
    pending.reserve(gpu::MAX_TREE_HEIGHT);
    std::uint32_t next_pair = 0;
    bool after_internal = false;  // node i - 1 was internal: its pair is next_pair - 1
    for (std::uint32_t i = 0; i < n; ++i) {
        const BvhNode& node = bvh.nodes[i];
        const std::uint32_t rank = next_pair;  // node i's pair, if it is internal
        if (i > 0 && after_internal) {
            gpu::BvhPair& p = pairs[next_pair - 1];
            set_child(node, rank, p.lo_a, p.hi_a, p.child_a, p.count_a);
        } else if (i > 0) {
            if (pending.empty() || pending.back().second_child != i) not_a_tree();
            gpu::BvhPair& p = pairs[pending.back().pair];
            pending.pop_back();
            set_child(node, rank, p.lo_b, p.hi_b, p.child_b, p.count_b);
        }
        after_internal = !is_leaf(node);
        if (after_internal) {
            if (next_pair == pairs.size()) not_a_tree();
            pending.push_back({next_pair++, node.index});
        }
    }
    if (!pending.empty() || next_pair != pairs.size()) not_a_tree();
    return pairs;
}

}  // namespace bvhlab
