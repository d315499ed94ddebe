// rebuild_top.h — the restructuring of a refitted tree's upper levels (adaptive, update.h): the
// nodes above a cut are rebuilt by binned SAH over the cut nodes' boxes, and the subtrees below
// the cut are kept whole (refitted) and moved under the new top.
#pragma once
#include <cstdint>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/update.h"

namespace bvhlab {

/// The cut the top rebuild works over: the topmost nodes of at most `max_primitives` primitives
/// (leaves where a larger subtree ends), and below them nodes whose children have come apart:
/// an inner node whose children's half areas sum to less than kApart of its own keeps its
/// children as cut nodes of their own (rigid parts of a subtree that have moved apart, the case
/// of objects flying past each other). In node order, none inside another.
std::vector<std::uint32_t> top_cut(const Bvh& tree, std::uint32_t max_primitives);

/// `tree` with its nodes above `cut` (top_cut) rebuilt by binned SAH over the cut nodes' boxes
/// (build_bvh_over_boxes: one box a leaf, the report's per-primitive SAH) and each cut node's
/// subtree moved whole below its new place, its leaf slots with it (leaf slots stay in
/// depth-first order). `built` (one cost per node when built) moves alike; the new top nodes get
/// their own, but the root keeps its entry (the cost the update aims for). The node count is the
/// old one (a full binary tree over the same cut). Reads no per-node costs (the subtrees' own are
/// summed as they are copied), so it follows a splice (rebuild_subtrees) without another pass
/// over the nodes. Returns false, `tree` untouched, where the new tree would pass MAX_TREE_HEIGHT
/// or its root has no area; else sets `sah_cost` to the new tree's.
bool rebuild_top(Bvh& tree, NodeCostArray& built, const std::vector<std::uint32_t>& cut, double& sah_cost);

}  // namespace bvhlab
