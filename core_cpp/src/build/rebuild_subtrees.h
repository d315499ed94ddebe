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
    /// The tree's SAH cost as stats and sah_cost() give it: cost[0] unrounded, or for a root of zero
    /// area (whose cost[0] is 0) the count sah_cost() gives, every node counted as hit.
    double root_cost = 0;

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

/// A subtree of a refitted tree rebuilt over its own primitives with the tree's settings, not yet
/// in the tree: its references and packed primitives name the original primitives, in the order
/// its leaves take the old subtree's slots [slot, slot + part.refs.size()).
struct RebuiltPart {
    std::uint32_t root = 0, end = 0;  ///< the old subtree's node range [root, end)
    std::uint32_t slot = 0;           ///< its first leaf slot
    Bvh part;
    NodeCosts costs;  ///< node_costs(part): its nodes' costs when built, areas and counts
};

/// The subtrees rooted at `roots` (node order, none inside another; `tree`'s slots in
/// depth-first order, as a refit leaves them) rebuilt, on up to tree.config.threads threads of
/// the pool (each part on one: the same parts on every thread count); `now` is node_costs(tree).
/// A part that would pass MAX_TREE_HEIGHT where it stands is dropped (its subtree kept).
/// `area_cost_saved` receives what the parts take off the root's A·cost (so the new tree's SAH
/// cost needs no pass over it).
std::vector<RebuiltPart> build_parts(const Bvh& tree, const std::vector<std::uint32_t>& roots,
                                     const GeometryView& geometry, const NodeCosts& now, double& area_cost_saved);

/// Writes the parts' references and packed primitives into their slots of `tree` (the same
/// primitives there, in the parts' leaf order). The nodes still hold the old subtrees.
void place_part_slots(Bvh& tree, const std::vector<RebuiltPart>& parts);

/// Replaces each part's old node range by the part's nodes in the depth-first array (one copy of
/// the nodes): every node index after a replaced range moves by the difference. `built` (one
/// per node, costs when built) is spliced alike, the parts' nodes getting their own.
void splice_parts(Bvh& tree, NodeCostArray& built, const std::vector<RebuiltPart>& parts);

/// The primitives the parts hold.
std::uint64_t primitives_in(const std::vector<RebuiltPart>& parts);

/// build_parts, place_part_slots and splice_parts: `tree` with the subtrees at `roots` rebuilt.
/// Returns the primitives rebuilt.
std::uint64_t rebuild_subtrees(Bvh& tree, NodeCostArray& built, const std::vector<std::uint32_t>& roots,
                               const GeometryView& geometry, const NodeCosts& now, double& area_cost_saved);

}  // namespace bvhlab
