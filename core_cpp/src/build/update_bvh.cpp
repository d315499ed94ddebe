// update_bvh.cpp — the update policies of update.h, their names and checks, and the per-node
// costs they compare.
#include "bvhlab/update.h"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "bvhlab/stats.h"
#include "rebuild_subtrees.h"

namespace bvhlab {
namespace {

using Clock = std::chrono::steady_clock;

constexpr std::string_view kNames[] = {"rebuild", "refit", "partial", "adaptive"};

/// The partial step after a refit: rebuild the subtrees past the threshold (Yoon et al. 2007's
/// selective restructuring, with the SAH cost ratio as the measure of a subtree gone bad).
/// Adaptive asks for a full rebuild instead (returns false) when they hold more than half the
/// primitives: the parts' gathering and splicing then cost more than a rebuild saves (bench/updates.py:
/// a partial update of most of a 250K-triangle wave took 87-94 ms against 39-65 ms for a rebuild).
bool restructure(Bvh& tree, std::vector<float>& built, const std::vector<float>& costs, const GeometryView& g,
                 const UpdateConfig& config, UpdateStats& stats) {
    const std::vector<std::uint32_t> roots =
        subtrees_past(tree, costs, built, config.subtree_growth, config.min_subtree_primitives);
    if (config.policy == UpdatePolicy::Adaptive && 2 * primitives_under(tree, roots) > g.primitive_count())
        return false;
    stats.primitives_rebuilt = rebuild_subtrees(tree, built, roots, g);
    stats.subtrees_rebuilt = static_cast<std::uint32_t>(roots.size());
    return true;
}

}  // namespace

std::vector<float> subtree_costs(const Bvh& bvh) {
    // S(n) and, for nodes of zero area, U(n): every node counted as hit
    std::vector<double> area_cost(bvh.nodes.size()), unit_cost(bvh.nodes.size());
    std::vector<float> out(bvh.nodes.size());
    for (std::size_t i = bvh.nodes.size(); i-- > 0;) {
        const BvhNode& n = bvh.nodes[i];
        const double area = node_box(n).half_area();
        if (is_leaf(n)) {
            area_cost[i] = area * leaf_count(n), unit_cost[i] = leaf_count(n);
        } else {
            area_cost[i] = area + area_cost[i + 1] + area_cost[n.index];
            unit_cost[i] = 1 + unit_cost[i + 1] + unit_cost[n.index];
        }
        out[i] = float(area > 0 ? area_cost[i] / area : unit_cost[i]);
    }
    return out;
}

Bvh update_bvh(const Bvh& old, const std::vector<float>& built, const GeometryView& g, const UpdateConfig& config,
               std::vector<float>& built_out, UpdateStats* stats_out) {
    validate(config);
    if (built.size() != old.nodes.size())
        throw std::invalid_argument("update: the built costs must have one entry per node of the tree");
    const auto start = Clock::now();
    UpdateStats stats;
    stats.policy = config.policy;
    Bvh tree;
    auto rebuild = [&] {
        tree = build_bvh(g, old.config);
        built_out = subtree_costs(tree);
        stats.policy = UpdatePolicy::Rebuild, stats.subtrees_rebuilt = 1,
        stats.primitives_rebuilt = g.primitive_count();
    };
    if (config.policy == UpdatePolicy::Rebuild) {
        rebuild();
    } else {
        tree = refitted(old, g, old.config.threads);
        built_out = built;
        if (config.policy != UpdatePolicy::Refit) {
            const std::vector<float> costs = subtree_costs(tree);
            const bool adaptive = config.policy == UpdatePolicy::Adaptive;
            if ((adaptive && !tree.empty() && costs[0] > config.tree_growth * built[0]) ||
                !restructure(tree, built_out, costs, g, config, stats)) {
                rebuild();
            } else if (adaptive) {
                stats.policy = stats.subtrees_rebuilt ? UpdatePolicy::Partial : UpdatePolicy::Refit;
            }
        }
    }
    stats.sah_cost = tree.empty() ? 0.0 : subtree_costs(tree)[0];
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
    if (static_cast<unsigned>(config.policy) >= std::size(kNames)) throw std::invalid_argument("unknown update policy");
}

}  // namespace bvhlab
