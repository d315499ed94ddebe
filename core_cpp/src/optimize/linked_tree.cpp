// linked_tree.cpp — a Bvh to linked nodes and back (linked_tree.h).
#include "linked_tree.h"

#include <algorithm>

#include "bvhlab/stats.h"

namespace bvhlab::optimize {
namespace {

/// The nodes of `tree` in preorder (left first), without recursion.
std::vector<std::uint32_t> preorder(const LinkedTree& tree) {
    std::vector<std::uint32_t> order, stack;
    if (tree.root == kNone) return order;
    order.reserve(tree.nodes.size());
    stack.push_back(tree.root);
    while (!stack.empty()) {
        const std::uint32_t n = stack.back();
        stack.pop_back();
        order.push_back(n);
        const LinkedNode& node = tree.nodes[n];
        if (!node.leaf()) stack.push_back(node.right), stack.push_back(node.left);
    }
    return order;
}

/// For each node: whether it becomes one leaf (the topmost such nodes are the ones flattened as
/// leaves), by the SAH with the tree's costs, children before parents (reverse preorder).
std::vector<char> leaves_to_merge(const LinkedTree& tree, const std::vector<std::uint32_t>& order,
                                  const BuildConfig& config) {
    std::vector<char> merge(tree.nodes.size(), 0);
    std::vector<double> cost(tree.nodes.size());
    std::vector<std::uint64_t> count(tree.nodes.size());
    for (auto it = order.rbegin(); it != order.rend(); ++it) {
        const LinkedNode& n = tree.nodes[*it];
        const double area = n.box.half_area();
        if (n.leaf()) {
            count[*it] = n.count, cost[*it] = area * n.count * config.intersection_cost;
            continue;
        }
        count[*it] = count[n.left] + count[n.right];
        const double split = area * config.traversal_cost + cost[n.left] + cost[n.right];
        const double as_leaf = area * double(count[*it]) * config.intersection_cost;
        merge[*it] = count[*it] <= config.max_leaf_size && as_leaf < split;
        cost[*it] = merge[*it] ? as_leaf : split;
    }
    return merge;
}

/// Appends the slots of every leaf under `n` (left first) to `slots`.
void gather_leaves(const LinkedTree& tree, std::uint32_t n, std::vector<std::uint32_t>& stack,
                   std::vector<std::uint32_t>& leaves) {
    stack.assign(1, n);
    while (!stack.empty()) {
        const LinkedNode& node = tree.nodes[stack.back()];
        const std::uint32_t at = stack.back();
        stack.pop_back();
        if (node.leaf()) leaves.push_back(at);
        else stack.push_back(node.right), stack.push_back(node.left);
    }
}

}  // namespace

LinkedTree link(const Bvh& bvh) {
    LinkedTree tree;
    tree.nodes.resize(bvh.nodes.size());
    for (std::uint32_t i = bvh.node_count(); i-- > 0;) {
        const BvhNode& b = bvh.nodes[i];
        LinkedNode& n = tree.nodes[i];
        n.box = node_box(b);
        if (is_leaf(b)) {
            n.first = b.index, n.count = leaf_count(b);
            continue;
        }
        n.left = i + 1, n.right = b.index;
        tree.nodes[n.left].parent = i, tree.nodes[n.right].parent = i;
        n.height = 1 + std::max(tree.nodes[n.left].height, tree.nodes[n.right].height);
    }
    if (!bvh.empty()) tree.root = 0;
    return tree;
}

Bvh flatten(const LinkedTree& tree, const Bvh& source, bool merge, std::uint64_t* merged) {
    Bvh out;
    out.triangle_count = source.triangle_count, out.sphere_count = source.sphere_count;
    out.set_fingerprint(source.fingerprint());
    out.config = source.config;
    out.build_ms = source.build_ms;
    if (tree.root == kNone) return out;
    const std::vector<std::uint32_t> order = preorder(tree);
    const std::vector<char> as_leaf =
        merge ? leaves_to_merge(tree, order, source.config) : std::vector<char>(tree.nodes.size(), 0);
    const bool packed = !source.prims.empty();
    out.refs = BigVector<std::uint32_t>(source.refs.size());
    if (packed) out.prims = BigVector<PackedPrim>(source.prims.size());
    std::vector<BvhNode> nodes;
    std::vector<std::uint8_t> depths;
    nodes.reserve(order.size()), depths.reserve(order.size());
    struct Item {
        std::uint32_t node, depth, second_of;  ///< second_of: the parent whose second child it is
    };
    std::vector<Item> stack{{tree.root, 0, kNone}};
    std::vector<std::uint32_t> scratch, leaves;
    std::uint32_t slot = 0;
    std::uint64_t merges = 0;
    while (!stack.empty()) {
        const Item item = stack.back();
        stack.pop_back();
        const LinkedNode& n = tree.nodes[item.node];
        const std::uint32_t at = static_cast<std::uint32_t>(nodes.size());
        if (item.second_of != kNone) nodes[item.second_of].index = at;
        BvhNode b{};
        set_box(b, n.box);
        if (n.leaf() || as_leaf[item.node]) {
            merges += !n.leaf();
            leaves.clear();
            gather_leaves(tree, item.node, scratch, leaves);
            b.index = slot;
            for (std::uint32_t l : leaves) {
                const LinkedNode& leaf = tree.nodes[l];
                std::copy_n(source.refs.begin() + leaf.first, leaf.count, out.refs.begin() + slot);
                if (packed) std::copy_n(source.prims.begin() + leaf.first, leaf.count, out.prims.begin() + slot);
                slot += leaf.count;
            }
            b.info = slot - b.index;
        } else {
            b.info = gpu::NODE_INTERNAL_BIT;  // its skip once its subtree is written
            stack.push_back({n.right, item.depth + 1, at});
            stack.push_back({n.left, item.depth + 1, kNone});
        }
        nodes.push_back(b), depths.push_back(static_cast<std::uint8_t>(item.depth));
    }
    // skip: the end of the subtree, which is the end of the second child's (written after it)
    std::vector<std::uint32_t> end(nodes.size());
    for (std::size_t i = nodes.size(); i-- > 0;) {
        BvhNode& b = nodes[i];
        if (is_leaf(b)) {
            end[i] = std::uint32_t(i + 1);
        } else {
            end[i] = end[b.index];
            b.info = gpu::NODE_INTERNAL_BIT | end[i];
        }
    }
    out.nodes = BigVector<BvhNode>(nodes.size());
    std::copy(nodes.begin(), nodes.end(), out.nodes.begin());
    out.depths = BigVector<std::uint8_t>(depths.size());
    std::copy(depths.begin(), depths.end(), out.depths.begin());
    if (merged) *merged = merges;
    return out;
}

}  // namespace bvhlab::optimize
