// update.h — updates of a tree over a deforming mesh (issue 34), one policy per update: rebuild,
// refit, partial (refit, then rebuild the subtrees whose SAH cost grew too much; selective
// restructuring, Yoon, Curtis and Manocha 2007), or adaptive (refit, then by the measured costs:
// nothing more, subtrees and the upper levels rebuilt, or a full rebuild). Every policy leaves a
// whole, valid tree (docs/design.md "Tree layout"); the same inputs give the same tree on any
// thread count.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "bvhlab/bvh.h"

namespace bvhlab {

enum class UpdatePolicy {
    Rebuild,   ///< a fresh build with the tree's own settings
    Refit,     ///< boxes only (refitted): the topology stays, its cost may grow
    Partial,   ///< refit, then rebuild each topmost subtree whose cost grew past subtree_growth
    Adaptive,  ///< refit; past target_growth, rebuild the subtrees holding most of the cost grown
               ///< per primitive, then the levels above a cut of small subtrees over their boxes
               ///< (a full rebuild when the tree still costs more than tree_growth)
};

/// The thresholds of an update. Costs are SAH costs of a subtree relative to its own root's area
/// (subtree_costs), compared with the same subtree's cost when it was built.
struct UpdateConfig {
    UpdatePolicy policy = UpdatePolicy::Adaptive;
    /// The whole rebuild's and the fresh reference build's progress (BuildConfig::progress): false
    /// stops the update (BuildCancelled), `old` untouched. Optional; refit and partial rebuild's
    /// parts take no calls (milliseconds each).
    ProgressCallback progress;
    /// partial: a subtree is rebuilt once its cost exceeds this times its cost when built (Yoon
    /// et al. 2007 restructure where culling efficiency has dropped; the ratio is that measure
    /// under the SAH). bench/updates.py, over 11 frames: 1.3 kept the SAH within 1.22x of a fresh
    /// build's for 0.56x the time of rebuilding every frame; 1.2 within 1.08x for 0.49x; 1.15
    /// within 1.03x for 0.84x; 1.1 rebuilt every frame.
    float subtree_growth = 1.2f;
    /// adaptive: while the refitted tree's cost is within this times its cost when built, the
    /// refit is all; past it, subtrees are rebuilt to take the excess off (subtrees_by_excess).
    float target_growth = 1.03f;
    /// adaptive: the most primitives one update rebuilds in subtrees, as a share of all (the
    /// subtrees that would not fit wait for the next update). 0.15 before rebuild_top; with it,
    /// 0.1 kept the bundled animations within 1.04-1.09 of a fresh build's SAH with no full
    /// rebuild (bench/updates.py; 0.05 let the generated crowd rebuild 10 frames of 23). With
    /// top_growth 1.085 (helper adaptive4, thread CPU time against rebuilding every frame, three
    /// rounds in one process, 0.1 → 0.08): wave_anim.blend's frames 0.436-0.444 → 0.398-0.422
    /// (worst SAH ÷ fresh 1.063 → 1.066), crowd_anim.blend's 0.403-0.411 → 0.385-0.394 (1.044 →
    /// 1.064), the generated crowd 0.537-0.555 → 0.514-0.530 (1.067 → 1.066), the generated wave
    /// 0.415-0.422 → 0.406-0.414 (1.067); 0.12 cost more everywhere, 0.05 rebuilt the generated
    /// crowd once (1.092).
    float restructure_share = 0.08f;
    /// adaptive: the whole tree is rebuilt instead when the restructured tree's cost still exceeds
    /// this times its reference: its cost when built, taken as keeping its A·cost where the root
    /// has grown since (update_bvh.cpp reference_cost; issue 34: within 1.10 of a fresh build's). Before
    /// rebuild_top, on the 24-frame wave: 1.09 kept the SAH within 1.065 of a fresh build's for
    /// 0.45-0.53 of the time of rebuilding every frame, rebuilding 4 frames; 1.15 within 1.12-1.14
    /// for 0.39-0.42; 1.05 within 1.03-1.04 for 0.60-0.65. (The add-on rebuilt at 1.5 of the
    /// refitted cost, addon/engine/scene_tree.py.)
    float tree_growth = 1.09f;
    /// partial, adaptive: subtrees of fewer primitives are never rebuilt alone (their rebuilds
    /// gain little and their costs are noisy); their ancestors are.
    std::uint32_t min_subtree_primitives = 256;
    /// adaptive: after the subtrees, the levels above the topmost subtrees of at most this many
    /// primitives are rebuilt over those subtrees' boxes (rebuild_top.h); 0: never. bench/
    /// updates.py, restructure_share 0.1: 16 kept the generated crowd within 1.085 of a fresh
    /// build's SAH with no full rebuild, 32 within 1.110, 64 rebuilt 12 frames of 23; the wave
    /// within 1.037 (16), 1.058 (32), 1.065 (0: no top rebuild). With tree_growth against a
    /// reference that follows a fresh build's cost (update_bvh.cpp reference_cost), 16 rebuilt 6
    /// of the generated crowd's 23 frames (0.78 of rebuilding every frame), 8 none (0.57-0.59,
    /// within 1.067; the wave 0.47-0.52, within 1.050; docs/design.md).
    std::uint32_t top_cut_primitives = 8;
    /// adaptive: the levels above the cut are rebuilt only while the tree, after its subtrees,
    /// still costs more than this times its cost when built (the step copies every node and builds
    /// over the cut's boxes: about a fifth of a rebuild in thread CPU time, the largest part of an
    /// update that runs it). Kept below tree_growth so that the top, not a full rebuild, takes the
    /// excess. Thread CPU time against rebuilding every frame in one process, two rounds (helper
    /// adaptive4; share / worst SAH ÷ fresh / frames of 23 running it): 1.085 on wave_anim.blend's
    /// frames 0.42-0.44 / 1.063 / 13 (1.07: 0.48-0.49 / 1.054 / 17), crowd_anim.blend's 0.40-0.41
    /// / 1.044 / 11 (0.41 / 1.047 / 12), the generated wave 0.42 / 1.067 / 11 (0.46 / 1.050 /
    /// 15), the generated crowd 0.54 / 1.067 / 23 (0.55, the same); 1.08 between; 1.088 let the
    /// .blend crowd reach 1.086.
    float top_growth = 1.085f;
    /// adaptive: in the top's cut, a subtree of at most this many primitives is also taken whole
    /// where it is as built: a subtree the update just rebuilt, or one whose cost relative to its
    /// own box is its cost when built (within 1e-5: its primitives moved as one, translated), so
    /// that the top is built over fewer boxes (rebuild_top.h top_cut); where that top would leave
    /// the tree past tree_growth, the top over the fine cut instead. 0: only top_cut_primitives.
    /// Thread CPU time against rebuilding every frame (helper adaptive7, 0 → 64; share / worst SAH
    /// ÷ fresh): the generated crowd 0.50-0.53 → 0.30-0.34 / 1.066 → 1.045, crowd_anim.blend's
    /// frames 0.35-0.37 → 0.29-0.30 / 1.064 → 1.059, the generated wave 0.37-0.39 → 0.34-0.36 /
    /// 1.067 → 1.060, wave_anim.blend's 0.37-0.39 → 0.36-0.39 / 1.066 → 1.059 (one top more, +1.3%
    /// instructions, the same time, worst SAH lower, the frames' summed SAH +0.8%); 512 took the
    /// generated crowd to 0.24-0.26 but the wave to 0.40 (docs/design.md has the others). 64 is the
    /// default: better on three animations, even on the fourth.
    std::uint32_t top_intact_primitives = 64;
    /// adaptive: where the top's first cut (top_cut_primitives, the intact subtrees whole) is
    /// dense, more than 0.1 boxes per primitive, it is taken again with subtrees of at most this
    /// many primitives; the fine cut alone stays the fallback where that top would leave the tree
    /// past tree_growth. 0 (or at most top_cut_primitives): never. On the waves no subtree is as
    /// built but the rebuilt parts, and the top's build over their ~40K boxes (0.15-0.17 a
    /// primitive; the crowds' 0.02-0.06, whose tops stay as they were) was the largest part of an
    /// update. Thread CPU time against rebuilding every frame (helper adaptive8, 0 → 24;
    /// bench/updates.py --interleaved, four rounds; share / worst SAH ÷ fresh): the generated
    /// wave 0.345-0.378 → 0.302-0.332 / 1.060 → 1.068, wave_anim.blend's frames 0.369-0.396 →
    /// 0.306-0.337 / 1.059 → 1.062, the crowds the same trees; 16 and 32 were dearer, 48 ran
    /// more tops (docs/design.md).
    std::uint32_t top_coarse_cut_primitives = 24;
    /// Also build a fresh tree over the geometry, only to report its SAH cost (UpdateStats::
    /// fresh_sah_cost): on demand, as it costs a build.
    bool measure_fresh = false;
};

/// What an update did.
struct UpdateStats {
    UpdatePolicy policy = UpdatePolicy::Refit;  ///< the policy that ran (adaptive's choice)
    double ms = 0;                              ///< wall time of the whole update
    double sah_cost = 0;                        ///< of the updated tree (sah_cost, stats.h)
    std::uint32_t subtrees_rebuilt = 0;         ///< partial: how many; rebuild: 1
    std::uint64_t primitives_rebuilt = 0;       ///< in the rebuilt subtrees
    std::uint32_t top_boxes = 0;                ///< adaptive: the cut's subtrees (rebuild_top); 0: none
    double fresh_sah_cost = -1;                 ///< a fresh build's, with UpdateConfig::measure_fresh; else -1
};

/// One cost per node of a tree (subtree_costs), in the builds' cached blocks (big_vector.h): an
/// update makes several, and a fresh std::vector of a 250K-triangle tree's size cost a page fault
/// per page (a quarter of a partial update's time).
using NodeCostArray = BigVector<float>;

/// Each node's SAH cost relative to its own box: S(n)/A(n) with S(leaf) = A·N and S(inner) =
/// A·C_trav + S(children) (C_trav = C_isect = 1, sah_cost's formula), so entry 0 is sah_cost(bvh)
/// (rounded to float) where the root has an area.
/// A node of zero area gets 0: a tree whose boxes had no area when built says nothing of the
/// geometry spread out again, so such a node counts as past any growth once it has an area (its
/// whole cost the excess: partial and adaptive rebuild it first) and never while it has none;
/// sah_cost of a tree with a root of zero area counts nodes instead.
NodeCostArray subtree_costs(const Bvh& bvh);

/// The tree over `geometry` (same counts) by `config.policy`, from `old` (untouched) and the
/// costs its nodes had when built (`built`, subtree_costs of the tree as built, one per node of
/// `old`, and after them, as update_bvh leaves them, the root's half area and the primitives' surface
/// area when entry 0, adaptive's reference, was taken: without them, `old`'s). `built_out` receives
/// those for the new tree (rebuilt nodes' own, the others' carried over, then the reference's two
/// figures). Throws
/// std::invalid_argument as refit and build_bvh do.
Bvh update_bvh(const Bvh& old, const NodeCostArray& built, const GeometryView& geometry, const UpdateConfig& config,
               NodeCostArray& built_out, UpdateStats* stats = nullptr);

std::vector<std::string_view> update_policy_names();
UpdatePolicy parse_update_policy(std::string_view name);  ///< throws std::invalid_argument listing the names
std::string to_string(UpdatePolicy policy);
/// Throws std::invalid_argument for thresholds below 1 or not finite.
void validate(const UpdateConfig& config);

}  // namespace bvhlab
