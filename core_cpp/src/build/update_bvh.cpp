// update_bvh.cpp — the update policies of update.h, their names and checks, and the per-node
// costs they compare.
#include "bvhlab/update.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "bvhlab/stats.h"
#include "rebuild_subtrees.h"

namespace bvhlab {
namespace {

using Clock = std::chrono::steady_clock;

constexpr std::string_view kNames[] = {"rebuild", "refit", "partial", "adaptive"};

/// The restructuring after a refit: rebuild `roots` and splice them in; returns the new tree's
/// SAH cost (from the old one's and what the new subtrees took off: no pass over the tree).
double restructure(Bvh& tree, NodeCostArray& built, const NodeCosts& now, const std::vector<std::uint32_t>& roots,
                   const GeometryView& g, UpdateStats& stats) {
    double saved = 0;
    stats.primitives_rebuilt = rebuild_subtrees(tree, built, roots, g, now, saved);
    stats.subtrees_rebuilt = static_cast<std::uint32_t>(roots.size());
    if (now.area[0] > 0) return (now.area_cost(0) - saved) / now.area[0];
    return subtree_costs(tree)[0];  // a root of zero area: its cost counts nodes
}

/// What adaptive runs after a refit, by the tree's measured costs (`now`) against its costs when
/// built: nothing more while the tree's cost is within target_growth of its cost when built;
/// else the subtrees that take most of the excess off per primitive (subtrees_by_excess: Yoon,
/// Curtis and Manocha 2007 restructure only where culling efficiency dropped; the SAH cost is
/// that measure), at most restructure_share of the primitives; a full rebuild instead when the
/// tree would keep more than tree_growth of its cost when built after them. bench/updates.py
/// has the figures.
UpdatePolicy adaptive_choice(const Bvh& tree, const NodeCosts& now, const NodeCostArray& built,
                             const UpdateConfig& config, std::vector<std::uint32_t>& roots) {
    if (tree.empty() || now.cost[0] <= config.target_growth * built[0]) return UpdatePolicy::Refit;
    if (now.area[0] <= 0) return UpdatePolicy::Rebuild;  // no areas to weigh the subtrees by
    const double excess = double(now.area[0]) * (double(now.cost[0]) - built[0]);
    double covered = 0;
    roots = subtrees_by_excess(tree, now, built, excess, config.min_subtree_primitives,
                               std::uint64_t(config.restructure_share * now.count[0]), covered);
    // the cost the restructured tree should have: past tree_growth, a rebuild instead
    if (now.cost[0] - covered / now.area[0] > config.tree_growth * built[0]) return UpdatePolicy::Rebuild;
    return UpdatePolicy::Partial;
}

}  // namespace

NodeCosts node_costs(const Bvh& bvh) {
    // S(n) and, for nodes of zero area, U(n): every node counted as hit
    BigVector<double> area_cost(bvh.nodes.size()), unit_cost(bvh.nodes.size());
    NodeCosts out{NodeCostArray(bvh.nodes.size()), NodeCostArray(bvh.nodes.size()),
                  BigVector<std::uint32_t>(bvh.nodes.size())};
    for (std::size_t i = bvh.nodes.size(); i-- > 0;) {
        const BvhNode& n = bvh.nodes[i];
        const double area = node_box(n).half_area();
        if (is_leaf(n)) {
            area_cost[i] = area * leaf_count(n), unit_cost[i] = leaf_count(n), out.count[i] = leaf_count(n);
        } else {
            area_cost[i] = area + area_cost[i + 1] + area_cost[n.index];
            unit_cost[i] = 1 + unit_cost[i + 1] + unit_cost[n.index];
            out.count[i] = out.count[i + 1] + out.count[n.index];
        }
        out.cost[i] = float(area > 0 ? area_cost[i] / area : unit_cost[i]);
        out.area[i] = float(area);
    }
    return out;
}

NodeCostArray subtree_costs(const Bvh& bvh) { return node_costs(bvh).cost; }

Bvh update_bvh(const Bvh& old, const NodeCostArray& built, const GeometryView& g, const UpdateConfig& config,
               NodeCostArray& built_out, UpdateStats* stats_out) {
    validate(config);
    if (built.size() != old.nodes.size())
        throw std::invalid_argument("update: the built costs must have one entry per node of the tree");
    const auto start = Clock::now();
    UpdateStats stats;
    stats.policy = config.policy;
    Bvh tree;
    auto rebuild = [&] {
        tree = build_bvh(g, old.config);
        const NodeCosts fresh = node_costs(tree);
        built_out = fresh.cost;
        stats.sah_cost = tree.empty() ? 0.0 : fresh.cost[0];
        stats.policy = UpdatePolicy::Rebuild, stats.subtrees_rebuilt = 1,
        stats.primitives_rebuilt = g.primitive_count();
    };
    // an SBVH refits by a rebuild (refitted), and its subtrees' references are not whole primitives
    if (config.policy == UpdatePolicy::Rebuild || old.config.method == SplitMethod::Sbvh) {
        rebuild();
    } else {
        tree = refitted(old, g, old.config.threads);
        const NodeCosts now = node_costs(tree);
        stats.sah_cost = tree.empty() ? 0.0 : now.cost[0];
        std::vector<std::uint32_t> roots;
        UpdatePolicy ran = UpdatePolicy::Refit;
        if (config.policy == UpdatePolicy::Partial) {
            roots = subtrees_past(tree, now, built, config.subtree_growth, config.min_subtree_primitives);
            ran = UpdatePolicy::Partial;
        } else if (config.policy == UpdatePolicy::Adaptive) {
            ran = adaptive_choice(tree, now, built, config, roots);
        }
        if (ran == UpdatePolicy::Rebuild) {
            rebuild();
        } else {
            built_out = built;
            if (!roots.empty()) {
                stats.sah_cost = restructure(tree, built_out, now, roots, g, stats);
                // the root's cost as built follows the best its restructured tree reached: the
                // geometry's own shape may have made a good tree cheaper than the first build
                built_out[0] = std::min(built_out[0], float(stats.sah_cost));
            }
            stats.policy = config.policy == UpdatePolicy::Adaptive && roots.empty() ? UpdatePolicy::Refit : ran;
        }
    }
    stats.ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (config.measure_fresh) {  // not part of the update's time
        const Bvh fresh = stats.policy == UpdatePolicy::Rebuild ? Bvh{} : build_bvh(g, old.config);
        stats.fresh_sah_cost = stats.policy == UpdatePolicy::Rebuild ? stats.sah_cost : sah_cost(fresh);
    }
    if (stats_out) *stats_out = stats;
    return tree;
}

std::vector<std::string_view> update_policy_names() { return {std::begin(kNames), std::end(kNames)}; }

UpdatePolicy parse_update_policy(std::string_view name) {
    for (std::size_t i = 0; i < std::size(kNames); ++i)
        if (kNames[i] == name) return static_cast<UpdatePolicy>(i);
    throw std::invalid_argument("unknown update policy '" + std::string(name) +
                                "'; expected one of: rebuild, refit, partial, adaptive");
}

std::string to_string(UpdatePolicy policy) { return std::string(kNames[static_cast<int>(policy)]); }

void validate(const UpdateConfig& config) {
    if (!(config.subtree_growth >= 1.0f) || !std::isfinite(config.subtree_growth))
        throw std::invalid_argument("subtree_growth must be a finite number of at least 1");
    if (!(config.tree_growth >= 1.0f) || !std::isfinite(config.tree_growth))
        throw std::invalid_argument("tree_growth must be a finite number of at least 1");
    if (!(config.target_growth >= 1.0f) || !std::isfinite(config.target_growth))
        throw std::invalid_argument("target_growth must be a finite number of at least 1");
    if (!(config.restructure_share > 0.0f && config.restructure_share <= 1.0f))
        throw std::invalid_argument("restructure_share must be a number in (0, 1]");
    if (static_cast<unsigned>(config.policy) >= std::size(kNames)) throw std::invalid_argument("unknown update policy");
}

}  // namespace bvhlab
