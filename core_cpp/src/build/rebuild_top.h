// rebuild_top.h — the restructuring of a refitted tree's upper levels (adaptive, update.h): the
// nodes above a cut are rebuilt by binned SAH over the cut nodes' boxes, and the subtrees below
// the cut are kept whole (refitted, or rebuilt by build_parts) and moved under the new top, their
// leaf slots left where they are.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/update.h"
#include "rebuild_subtrees.h"

namespace bvhlab {

/// A node of a refitted tree whose rebuilt parts (build_parts) are not spliced in yet: `part` -1
/// names the tree's own node, k the node of parts[k].part (the part's root stands where the
/// tree's node parts[k].root was).
struct PartNode {
    std::int32_t part = -1;
    std::uint32_t node = 0;
    bool operator==(const PartNode& o) const { return part == o.part && node == o.node; }
};

/// The tree with its parts in place, read through PartNode (the parts' slots already placed,
/// place_part_slots): what the nodes, counts and costs of the tree after splice_parts would be,
/// without the copy of the nodes that splicing takes.
class PartedTree {
public:
    /// `now`: node_costs(tree); `parts` in node order (as build_parts gives them).
    /// `built`: the tree's nodes' costs when built (update.h), for top_cut's intact subtrees; null: none.
    PartedTree(const Bvh& tree, const NodeCosts& now, const std::vector<RebuiltPart>& parts,
               const NodeCostArray* built = nullptr);

    const BvhNode& node(PartNode n) const { return n.part < 0 ? tree_.nodes[n.node] : part(n).nodes[n.node]; }
    std::uint32_t count(PartNode n) const { return costs(n).count[n.node]; }
    /// S(n) = A(n)·cost(n): its share of the root's A·cost, in the root's units.
    double area_cost(PartNode n) const { return costs(n).area_cost(n.node); }

    const Bvh& tree() const { return tree_; }
    const NodeCosts& tree_costs() const { return now_; }
    const std::vector<RebuiltPart>& parts() const { return parts_; }
    const NodeCostArray* built() const { return built_; }

private:
    const Bvh& part(PartNode n) const { return parts_[std::size_t(n.part)].part; }
    const NodeCosts& costs(PartNode n) const { return n.part < 0 ? now_ : parts_[std::size_t(n.part)].costs; }

    const Bvh& tree_;
    const NodeCosts& now_;
    const std::vector<RebuiltPart>& parts_;
    const NodeCostArray* built_;
};

/// The cut the top rebuild works over: the topmost nodes of at most `max_primitives` primitives
/// (leaves where a larger subtree ends), and below them nodes whose children have come apart:
/// an inner node whose children's half areas sum to less than kApart of its own keeps its
/// children as cut nodes of their own (rigid parts of a subtree that have moved apart, the case
/// of objects flying past each other). Every cut node is a leaf or holds at most
/// `max_primitives` (or `intact_primitives`, below); none lies inside another, nor holds a part
/// inside it; in depth-first order. With `intact_primitives` above max_primitives, a node of at most that many primitives whose
/// cost is within kIntact of its cost when built (PartedTree::built; a rebuilt part's nodes: as
/// built) is a cut node too, whole: its primitives moved together (translated), so its insides
/// are as good as when built and only where it stands changed.
std::vector<PartNode> top_cut(const PartedTree& tree, std::uint32_t max_primitives,
                              std::uint32_t intact_primitives = 0);

/// top_cut for two sizes in one scan, for a caller that takes the coarse cut where the fine one
/// is dense: while `fine` holds at most `dense` nodes, it is top_cut(tree, fine_primitives,
/// intact_primitives), and `coarse` receives top_cut(tree, coarse_primitives, intact_primitives)
/// (fine_primitives at most coarse_primitives, else std::invalid_argument). Returns whether the
/// fine cut passed `dense` nodes: its scan stopped there (`fine` then holds its first dense + 1
/// nodes) and the coarse cut's went on alone. Two scans, the fine one and then the coarse one,
/// missed the cache at every jump over a cut subtree (adaptive's dense waves).
bool top_cuts(const PartedTree& tree, std::uint32_t fine_primitives, std::uint32_t coarse_primitives,
              std::uint32_t intact_primitives, std::size_t dense, std::vector<PartNode>& fine,
              std::vector<PartNode>& coarse);

/// What the top needs of each cut node, read in cut (depth-first) order: its box, the nodes of
/// its subtree, its primitives and S = A·cost.
struct CutInfo {
    BigVector<Aabb> boxes;
    BigVector<std::uint32_t> size, count;
    BigVector<double> area_cost;
};
CutInfo cut_info(const PartedTree& parted, const std::vector<PartNode>& cut);

/// A new top over the cut's boxes: the builder of every tree with the tree's settings
/// (build_bvh_over_boxes: one box a leaf, the report's per-primitive SAH).
Bvh built_top(const BuildConfig& tree_config, const CutInfo& info);

/// The SAH cost the tree would have with `top` above the cut (rebuild_top's `sah_cost`), without
/// the copy: each top node's half area and each cut node's S.
double top_sah_cost(const Bvh& top, const CutInfo& info);

/// The tree with its nodes above `cut` (top_cut) replaced by `top` (a tree over the cut's boxes,
/// built_top: leaf j holds one reference, top.refs[j], the cut node it stands for) and each cut
/// node's subtree moved whole below its new place; written into `tree` (its nodes and depths; the slots
/// stay: the parts' must be placed already) with the parts spliced in, so it replaces
/// splice_parts. A cut subtree's leaves keep their slots, so the leaves are no longer in
/// depth-first order of slots (each leaf's run whole; the next refit lays them in order again).
/// `built` (one cost per node when built) moves alike; the new top nodes get their own, but the
/// root keeps its entry (the cost the update aims for). Reads no costs but the cut nodes'
/// (PartedTree::area_cost). Returns false, `tree` untouched, where the new tree would pass
/// MAX_TREE_HEIGHT or its root has no area; else sets `sah_cost` to the new tree's.
bool rebuild_top(Bvh& tree, NodeCostArray& built, const PartedTree& parted, const std::vector<PartNode>& cut,
                 const CutInfo& info, const Bvh& top, double& sah_cost);

}  // namespace bvhlab
