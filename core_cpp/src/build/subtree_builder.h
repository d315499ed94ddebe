// subtree_builder.h — the one top-down builder (report §2.3): it owns the work stack, asks the
// configured split method where to split, and writes nodes in depth-first order.
#pragma once
#include <atomic>
#include <functional>
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
    std::uint8_t buffer = 0;     ///< which of the two reference buffers holds the range
};

/// Nodes of one subtree in depth-first order, and the ranges it left for other threads.
struct Subtree {
    BigVector<BvhNode> nodes;
    BigVector<std::uint8_t> depths;
    std::vector<std::pair<std::uint32_t, WorkItem>> deferred;  ///< placeholder node, its range
};

/// State shared by every thread of one build.
struct BuildShared {
    PrimRef* buffers[2];          ///< ping-pong reference buffers (split.h)
    std::uint32_t* leaf_refs;     ///< output: the references in leaf order
    const BuildConfig& config;
    std::atomic<std::uint64_t> primitives_in_leaves{0};
    std::atomic<bool> cancelled{false};
};

/// Builds the subtree of `root` into `out`. Ranges of at most `defer_size` primitives (other than
/// the root) are not built but left in out.deferred as placeholder nodes; 0 defers nothing.
/// `on_progress` is called every few thousand nodes (from this thread).
void build_subtree(BuildShared& shared, SplitScratch& scratch, const WorkItem& root, Subtree& out,
                   std::uint32_t defer_size, const std::function<void()>& on_progress);

/// Decides a node: the split to make, or nothing for a leaf. Exposed for the tests.
std::optional<Split> choose_split(SplitContext& ctx, const WorkItem& item);

}  // namespace bvhlab
