// optimize.cpp — optimized(): batches of reinsertions (Bittner, Hapala and Havran 2013 §3.4) on
// a linked copy of the tree, then the flattened result (optimize.h).
#include "bvhlab/optimize.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "bvhlab/stats.h"
#include "linked_tree.h"
#include "reinsertion.h"

namespace bvhlab {
namespace {

using Clock = std::chrono::steady_clock;

struct Scored {
    float inefficiency;
    std::uint32_t node;
    bool operator<(const Scored& o) const {  // worst first; ties by index, so one order on every machine
        return inefficiency > o.inefficiency || (inefficiency == o.inefficiency && node < o.node);
    }
};

/// The worst `fraction` of the nodes that may be taken out and have not been in vain (`tried`),
/// worst first.
std::vector<Scored> worst_nodes(const optimize::LinkedTree& tree, const std::vector<char>& tried, float fraction) {
    std::vector<Scored> scored;
    for (std::uint32_t n = 0; n < tree.nodes.size(); ++n)
        if (!tried[n] && optimize::can_take_out(tree, n)) scored.push_back({optimize::inefficiency(tree, n), n});
    const std::size_t k =
        std::min(scored.size(), std::max<std::size_t>(1, std::size_t(std::ceil(double(fraction) * scored.size()))));
    std::nth_element(scored.begin(), scored.begin() + std::ptrdiff_t(k), scored.end());
    scored.resize(k);
    std::sort(scored.begin(), scored.end());
    return scored;
}

}  // namespace

Bvh optimized(const Bvh& tree, const OptimizeConfig& config, Cancellation* cancel, OptimizeStats* stats_out) {
    validate(config);
    const auto start = Clock::now();
    auto elapsed_ms = [&] { return std::chrono::duration<double, std::milli>(Clock::now() - start).count(); };
    OptimizeStats local;
    OptimizeStats& stats = stats_out ? *stats_out : local;  // filled as it goes: a progress check reads it
    stats = {};
    stats.sah_before = sah_cost(tree);
    stats.stop = OptimizeStop::Iterations;
    optimize::LinkedTree linked = optimize::link(tree);
    optimize::Reinserter reinserter(linked);
    // A node whose reinsertion gained nothing is not taken out again: the next batch moves on to
    // the next worst instead of trying the same ones (which stalled Sponza after 20 batches).
    std::vector<char> tried(linked.nodes.size(), 0);
    bool out_of_time = false;
    for (; stats.iterations < config.iterations && !out_of_time; ++stats.iterations) {
        std::uint64_t kept = 0;
        const std::vector<Scored> batch = worst_nodes(linked, tried, config.batch_fraction);
        if (batch.empty()) {
            stats.stop = OptimizeStop::Converged;
            break;
        }
        for (const Scored& s : batch) {
            if ((stats.attempts & 31) == 0) {
                if (cancel && cancel->poll()) throw Cancelled();
                if (config.time_budget_ms > 0 && elapsed_ms() >= config.time_budget_ms) {
                    out_of_time = true;
                    break;
                }
            }
            if (!optimize::can_take_out(linked, s.node)) continue;  // an earlier one moved it
            ++stats.attempts;
            const bool better = reinserter.reinsert_children(s.node);
            kept += better;
            tried[s.node] = !better;
        }
        stats.reinsertions += kept;
        if (out_of_time) stats.stop = OptimizeStop::TimeBudget;
    }
    if (cancel && cancel->poll()) throw Cancelled();
    Bvh out = optimize::flatten(linked, tree, config.merge_leaves, &stats.leaves_merged);
    stats.sah_after = sah_cost(out);
    if (stats.sah_after > stats.sah_before || compute_stats(out).height > gpu::MAX_TREE_HEIGHT) {
        out = optimize::flatten(optimize::link(tree), tree, false);  // never worse than it was (a guard)
        stats.sah_after = stats.sah_before, stats.reinsertions = 0, stats.leaves_merged = 0;
    }
    stats.ms = elapsed_ms();
    return out;
}

void validate(const OptimizeConfig& config) {
    if (!std::isfinite(config.time_budget_ms) || config.time_budget_ms < 0)
        throw std::invalid_argument("time_budget_ms must be a finite number of ms, at least 0 (0: no budget)");
    if (!(config.batch_fraction > 0.0f && config.batch_fraction <= 1.0f))
        throw std::invalid_argument("batch_fraction must be in (0, 1]");
}

std::string to_string(OptimizeStop stop) {
    switch (stop) {
        case OptimizeStop::Converged:
            return "converged";
        case OptimizeStop::Iterations:
            return "iterations";
        case OptimizeStop::TimeBudget:
            return "time_budget";
    }
    return "?";
}

}  // namespace bvhlab
