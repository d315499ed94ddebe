#include "assemble.h"

#include <algorithm>

#include "bvhlab/thread_pool.h"

namespace bvhlab {

namespace {

/// Skip index (and box) of internal node `n` from its children, which come after it.
void finish_internal(BvhNode& n, const BvhNode& first, const BvhNode& second, bool boxes_from_children) {
    n.info = gpu::NODE_INTERNAL_BIT | skip_index(second, n.index);
    if (!boxes_from_children) return;
    Aabb box = node_box(first);
    box.grow(node_box(second));
    set_box(n, box);
}

}  // namespace

void fill_boxes_from_children(BigVector<BvhNode>& nodes) {
    for (std::size_t i = nodes.size(); i-- > 0;) {
        BvhNode& n = nodes[i];
        if (!is_leaf(n)) finish_internal(n, nodes[i + 1], nodes[n.index], true);
    }
}

namespace {

/// Copies subtree `p` to out[base...], shifting its child and skip indices by base.
void copy_part(const Subtree& p, std::uint32_t base, Bvh& out) {
    // Whether a node is a leaf is data: the shift is selected, not branched on (a branch here
    // mispredicted about every other node).
    for (std::size_t j = 0; j < p.nodes.size(); ++j) {
        BvhNode n = p.nodes[j];
        const std::uint32_t shift = is_leaf(n) ? 0u : base;
        n.index += shift, n.info += shift;  // the skip keeps NODE_INTERNAL_BIT
        out.nodes[base + j] = n;
    }
    std::copy(p.depths.begin(), p.depths.end(), out.depths.begin() + base);
}

}  // namespace

void assemble(const Subtree& top, const std::vector<Subtree>& parts, unsigned threads, bool boxes_from_children,
              Bvh& out) {
    // final index of each top node: shifted by the extra nodes of the placeholders before it
    std::vector<std::uint32_t> final_index(top.nodes.size());
    std::vector<int> part_of(top.nodes.size(), -1);
    for (std::size_t k = 0; k < top.deferred.size(); ++k) part_of[top.deferred[k].node] = int(k);
    std::uint32_t shift = 0;
    for (std::size_t i = 0; i < top.nodes.size(); ++i) {
        final_index[i] = std::uint32_t(i) + shift;
        if (part_of[i] >= 0) shift += std::uint32_t(parts[part_of[i]].nodes.size() - 1);
    }
    out.nodes.resize(top.nodes.size() + shift);
    out.depths.resize(out.nodes.size());
    ThreadPool::shared().run(parts.size(), threads, [&](std::size_t k, unsigned) {
        copy_part(parts[k], final_index[top.deferred[k].node], out);
    });
    // The top nodes, backwards: a node's skip is its second child's, which comes later.
    for (std::size_t i = top.nodes.size(); i-- > 0;) {
        if (part_of[i] >= 0) continue;
        BvhNode n = top.nodes[i];
        const std::uint32_t at = final_index[i];
        if (!is_leaf(n)) {
            n.index = final_index[n.index];
            finish_internal(n, out.nodes[at + 1], out.nodes[n.index], boxes_from_children);
        }
        out.nodes[at] = n;
        out.depths[at] = top.depths[i];
    }
}

}  // namespace bvhlab
