// top_down_builder.h — the one top-down builder (report §2.3): it owns the work stack, asks the
// configured split method where to split, and writes nodes in depth-first order.
#pragma once
#include <atomic>
#include <cstdint>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/split.h"

namespace bvhlab {

/// A range still to be turned into a subtree.
struct WorkItem {
    Range range;
    NodeBounds bounds;
    std::uint32_t parent = 0;    ///< node whose second-child index this item's node fills in
    std::uint32_t depth = 0;
    bool second_child = false;
};

/// Nodes of one subtree in depth-first order, and the ranges it left for other threads.
struct Subtree {
    std::vector<BvhNode> nodes;
    std::vector<std::uint8_t> depths;
    std::vector<std::pair<std::uint32_t, WorkItem>> deferred;  ///< placeholder node, its range
};

/// State shared by every thread of one build.
struct BuildShared {
    PrimRef* refs;
    const BuildConfig& config;
    std::atomic<std::uint64_t> primitives_in_leaves{0};
    std::atomic<bool> cancelled{false};
};

/// Builds the subtree of `root` into `out`. Ranges of at most `defer_size` primitives (other than
/// the root) are not built but left in out.deferred as placeholder nodes; 0 defers nothing.
/// `on_progress` is called every few thousand nodes (from this thread).
template <class OnProgress>
void build_subtree(BuildShared& shared, SplitScratch& scratch, const WorkItem& root, Subtree& out,
                   std::uint32_t defer_size, OnProgress&& on_progress);

/// Decides a node: the split to make, or nothing for a leaf. Exposed for the tests.
std::optional<Split> choose_split(SplitContext& ctx, const WorkItem& item);

// ---- implementation of the template ----

void make_leaf(BvhNode& node, const WorkItem& item);

template <class OnProgress>
void build_subtree(BuildShared& shared, SplitScratch& scratch, const WorkItem& root, Subtree& out,
                   std::uint32_t defer_size, OnProgress&& on_progress) {
    SplitContext ctx{shared.refs, shared.config, scratch};
    std::vector<WorkItem> stack{root};
    std::uint32_t since_progress = 0;
    while (!stack.empty()) {
        WorkItem item = stack.back();
        stack.pop_back();
        auto index = static_cast<std::uint32_t>(out.nodes.size());
        out.nodes.emplace_back();
        out.depths.push_back(static_cast<std::uint8_t>(item.depth));
        if (item.second_child) out.nodes[item.parent].index = index;
        set_box(out.nodes[index], item.bounds.box);

        if (index > 0 && item.range.size() <= defer_size) {
            out.deferred.emplace_back(index, item);
            continue;
        }
        if (++since_progress == 4096) {
            since_progress = 0;
            on_progress();
            if (shared.cancelled.load(std::memory_order_relaxed)) return;
        }
        std::optional<Split> split = choose_split(ctx, item);
        if (!split) {
            make_leaf(out.nodes[index], item);
            shared.primitives_in_leaves.fetch_add(item.range.size(), std::memory_order_relaxed);
            continue;
        }
        out.nodes[index].info = gpu::NODE_INTERNAL_BIT;  // the skip index is filled in at the end
        const std::uint32_t d = item.depth + 1;
        stack.push_back({{split->mid, item.range.end}, split->right, index, d, true});
        stack.push_back({{item.range.begin, split->mid}, split->left, index, d, false});
    }
}

}  // namespace bvhlab
