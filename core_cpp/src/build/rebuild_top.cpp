// rebuild_top.cpp — rebuilding a refitted tree above a cut (rebuild_top.h). A refit keeps each
// subtree's own shape but not how the subtrees are grouped: where geometry moves, the large nodes'
// boxes span parts that were near each other when built. No subtree of a share of the primitives
// holds that excess, and rebuilding from primitives the nodes that do is a full rebuild. The levels
// above a cut of subtrees, each taken as one box, are rebuilt instead: a build over a few thousand
// boxes and one copy of the nodes and leaf slots. (HLBVH builds its upper levels by the SAH over
// clusters' boxes the same way, Pantaleoni and Luebke 2010; Garanzha, Pantaleoni and McAllister
// 2011. bench/updates.py: on the 24-frame wave, after the subtrees of adaptive, no more full
// rebuilds.)
#include "rebuild_top.h"

#include <algorithm>
#include <cstring>

namespace bvhlab {
namespace {

/// Children whose half areas sum to less than this share of their parent's have come apart.
constexpr float kApart = 0.5f;

/// The first leaf slot of the subtree at `j` (its leftmost leaf's; the slot count for j = node
/// count): a subtree's primitives are the slots up to the next one's.
std::uint32_t slot_at(const Bvh& tree, std::uint32_t j) {
    if (j == tree.node_count()) return static_cast<std::uint32_t>(tree.refs.size());
    while (!is_leaf(tree.nodes[j])) ++j;
    return tree.nodes[j].index;
}

/// The primitives under node i.
std::uint32_t primitives_at(const Bvh& tree, std::uint32_t i) {
    return slot_at(tree, skip_index(tree.nodes[i], i)) - slot_at(tree, i);
}

float half_area(const BvhNode& n) { return node_box(n).half_area(); }

}  // namespace

std::vector<std::uint32_t> top_cut(const Bvh& tree, std::uint32_t max_primitives) {
    std::vector<std::uint32_t> cut;
    for (std::uint32_t i = 0; i < tree.node_count();) {
        const BvhNode& n = tree.nodes[i];
        const bool apart =
            !is_leaf(n) && half_area(tree.nodes[i + 1]) + half_area(tree.nodes[n.index]) < kApart * half_area(n);
        if (is_leaf(n) || (!apart && primitives_at(tree, i) <= max_primitives)) {
            cut.push_back(i);
            i = skip_index(n, i);
        } else {
            ++i;  // its children (at i + 1 and after its first child's subtree) come next
        }
    }
    return cut;
}

bool rebuild_top(Bvh& tree, NodeCostArray& built, const std::vector<std::uint32_t>& cut, double& sah_cost) {
    if (tree.empty() || !(half_area(tree.nodes[0]) > 0)) return false;
    std::vector<Aabb> boxes(cut.size());
    for (std::size_t c = 0; c < cut.size(); ++c) boxes[c] = node_box(tree.nodes[cut[c]]);
    BuildConfig config = tree.config;
    config.max_leaf_size = 1, config.sah_block = 1, config.threads = 1, config.progress = nullptr;
    const Bvh top = build_bvh_over_boxes(boxes.data(), boxes.size(), config);
    // where each top node lands: after the top nodes before it and the cut subtrees they hold
    const std::uint32_t top_nodes = top.node_count();
    std::vector<std::uint32_t> at(top_nodes + 1);
    std::uint32_t height = 0;
    for (std::uint32_t j = 0, pos = 0; j <= top_nodes; ++j) {
        at[j] = pos;
        if (j == top_nodes) break;
        const BvhNode& n = top.nodes[j];
        if (!is_leaf(n)) {
            ++pos;
            continue;
        }
        if (leaf_count(n) != 1) return false;  // one box a leaf (max_leaf_size 1)
        const std::uint32_t c = cut[top.refs[n.index]];
        const std::uint32_t end = skip_index(tree.nodes[c], c);
        std::uint32_t deepest = 0;
        for (std::uint32_t i = c; i < end; ++i) deepest = std::max<std::uint32_t>(deepest, tree.depths[i]);
        height = std::max(height, top.depths[j] + deepest - tree.depths[c] + 1);
        pos += end - c;
    }
    if (height > gpu::MAX_TREE_HEIGHT) return false;
    // the new arrays: top inner nodes with their children's places, cut subtrees shifted whole
    Bvh out;
    out.nodes = BigVector<BvhNode>(tree.nodes.size());
    out.depths = BigVector<std::uint8_t>(tree.nodes.size());
    out.refs = BigVector<std::uint32_t>(tree.refs.size());
    out.prims = BigVector<PackedPrim>(tree.prims.size());
    NodeCostArray out_built(tree.nodes.size());
    // S(n) = A(n)·cost(n) of each top node, for its cost (built) and the tree's SAH cost
    std::vector<double> area_cost(top_nodes);
    std::uint32_t slot = 0;
    for (std::uint32_t j = 0; j < top_nodes; ++j) {
        const BvhNode& n = top.nodes[j];
        if (!is_leaf(n)) {
            BvhNode& o = out.nodes[at[j]];
            o = n;
            o.index = at[n.index], o.info = gpu::NODE_INTERNAL_BIT | at[skip_index(n, j)];
            out.depths[at[j]] = top.depths[j];
            continue;
        }
        const std::uint32_t c = cut[top.refs[n.index]];
        const std::uint32_t end = skip_index(tree.nodes[c], c);
        const std::uint32_t first_slot = slot_at(tree, c), count = slot_at(tree, end) - first_slot;
        const std::int64_t shift = std::int64_t(at[j]) - c, slot_shift = std::int64_t(slot) - first_slot;
        const int depth_shift = int(top.depths[j]) - int(tree.depths[c]);
        double area_cost_below = 0;  // S(c): each node's half area, times its count for a leaf
        for (std::uint32_t i = c; i < end; ++i) {
            BvhNode m = tree.nodes[i];
            if (is_leaf(m)) {
                area_cost_below += double(half_area(m)) * leaf_count(m);
                m.index = std::uint32_t(m.index + slot_shift);
            } else {
                area_cost_below += half_area(m);
                m.index = std::uint32_t(m.index + shift);
                m.info = gpu::NODE_INTERNAL_BIT | std::uint32_t(skip_index(m, i) + shift);
            }
            out.nodes[i + shift] = m;
            out.depths[i + shift] = std::uint8_t(tree.depths[i] + depth_shift);
        }
        std::memcpy(out_built.data() + at[j], built.data() + c, (end - c) * sizeof(float));
        std::memcpy(out.refs.data() + slot, tree.refs.data() + first_slot, count * sizeof(std::uint32_t));
        std::memcpy(out.prims.data() + slot, tree.prims.data() + first_slot, count * sizeof(PackedPrim));
        slot += count;
        area_cost[j] = area_cost_below;
    }
    // the top's costs, children before parents (both after their parent in depth-first order)
    for (std::uint32_t j = top_nodes; j-- > 0;) {
        const BvhNode& n = top.nodes[j];
        if (is_leaf(n)) continue;
        const double area = node_box(n).half_area();
        area_cost[j] = area + area_cost[j + 1] + area_cost[n.index];
        // a node of zero area weighs nothing in any excess (A·(cost - built)): any cost will do
        out_built[at[j]] = float(area > 0 ? area_cost[j] / area : 1.0);
    }
    out_built[0] = built[0];  // the root's cost when built stays the update's reference
    sah_cost = area_cost[0] / node_box(top.nodes[0]).half_area();  // the old root's box: not 0
    tree.nodes = std::move(out.nodes), tree.depths = std::move(out.depths);
    tree.refs = std::move(out.refs), tree.prims = std::move(out.prims);
    built = std::move(out_built);
    return true;
}

}  // namespace bvhlab
