// rebuild_subtrees.h — the restructuring step of the partial and adaptive updates (update.h):
// which subtrees of a refitted tree to rebuild, and rebuilding them from scratch in place.
#pragma once
#include <cstdint>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/update.h"

namespace bvhlab {

/// Per node of a tree, from one backward pass over it: its SAH cost relative to its own box
/// (update.h subtree_costs), its half area and the primitives under it.
struct NodeCosts {
    NodeCostArray cost, area;
    BigVector<std::uint32_t> count;

    /// S(n) = A(n)·cost(n): node i's share of the root's A·cost, in the root's units.
    double area_cost(std::uint32_t i) const { return double(area[i]) * cost[i]; }
};
NodeCosts node_costs(const Bvh& bvh);

/// The topmost nodes whose subtree cost exceeds `growth` × `built` and which hold at least
/// `min_primitives` primitives, in node order (partial).
std::vector<std::uint32_t> subtrees_past(const Bvh& bvh, const NodeCosts& now, const NodeCostArray& built, float growth,
                                         std::uint32_t min_primitives);

/// Adaptive's choice: subtrees (of at least `min_primitives`, none inside another, in node
/// order) whose rebuild takes the most cost off per primitive rebuilt, until their excess covers
/// `to_remove` (in A·cost units) or they would hold more than `max_primitives`. A node's excess is A(n)·(cost(n) - built(n)): what a rebuild
/// restoring its cost when built takes off the root's A·cost. A node whose excess its children
/// mostly hold is passed over for them (rebuilding it would redo their siblings' good parts too).
/// `covered` receives the excess the chosen subtrees hold.
std::vector<std::uint32_t> subtrees_by_excess(const Bvh& bvh, const NodeCosts& now, const NodeCostArray& built,
                                              double to_remove, std::uint32_t min_primitives,
                                              std::uint64_t max_primitives, double& covered);

/// The primitives under the nodes `roots` (none inside another).
std::uint64_t primitives_under(const NodeCosts& now, const std::vector<std::uint32_t>& roots);

/// `tree` with the subtrees rooted at `roots` (node order, none inside another) each rebuilt over
/// its own primitives with the tree's settings, spliced in place of the old ones; `built` (one per
/// node, costs when built) is spliced alike, the rebuilt nodes getting their own. `now` is
/// node_costs(tree) before. Returns the primitives rebuilt; `area_cost_saved` receives what the
/// new subtrees took off the root's A·cost (so the new tree's SAH cost needs no pass over it). A
/// subtree whose rebuild would pass MAX_TREE_HEIGHT is kept as it was.
std::uint64_t rebuild_subtrees(Bvh& tree, NodeCostArray& built, const std::vector<std::uint32_t>& roots,
                               const GeometryView& geometry, const NodeCosts& now, double& area_cost_saved);

}  // namespace bvhlab
