// rebuild_subtrees.h — the partial update's restructuring step (update.h): rebuild chosen
// subtrees of a refitted tree from scratch and splice them in.
#pragma once
#include <cstdint>
#include <vector>

#include "bvhlab/bvh.h"

namespace bvhlab {

/// The topmost nodes whose subtree cost (`costs`, subtree_costs) exceeds `growth` × `built` and
/// which hold at least `min_primitives` primitives, in node order.
std::vector<std::uint32_t> subtrees_past(const Bvh& bvh, const std::vector<float>& costs,
                                         const std::vector<float>& built, float growth, std::uint32_t min_primitives);

/// The primitives under the nodes `roots` (none inside another).
std::uint64_t primitives_under(const Bvh& bvh, const std::vector<std::uint32_t>& roots);

/// `tree` with the subtrees rooted at `roots` (node order, none inside another) each rebuilt over
/// its own primitives with the tree's settings, spliced in place of the old ones; `built` (one per
/// node, costs when built) is spliced alike, the rebuilt nodes getting their own. Returns the
/// primitives rebuilt. A subtree whose rebuild would pass MAX_TREE_HEIGHT is kept as it was.
std::uint64_t rebuild_subtrees(Bvh& tree, std::vector<float>& built, const std::vector<std::uint32_t>& roots,
                               const GeometryView& geometry);

}  // namespace bvhlab
