// optimize.h — a built tree made cheaper after the build by reinsertion (Bittner, Hapala and
// Havran 2013, "Fast insertion-based optimization of bounding volume hierarchies"; the sequential
// algorithm, not Meister and Bittner 2018's parallel one): the nodes that look worst are taken out
// and their two children put back where the surface area heuristic finds them cheapest. Leaves
// move whole (their primitives and sizes stay), so no geometry is needed; after the last batch,
// subtrees of at most max_leaf_size primitives that are cheaper as one leaf become one.
#pragma once
#include <cstdint>
#include <string>

#include "bvhlab/bvh.h"
#include "bvhlab/cancel.h"

namespace bvhlab {

/// How long an optimisation runs and how much it takes out at once.
struct OptimizeConfig {
    /// Batches at most: each scores every node and reinserts the worst `batch_fraction` of those
    /// not yet taken out in vain (Bittner et al. 2013 §3.4). It stops earlier when none is left.
    /// Sponza's default tree (SAH 71.1, one core): 10 batches 60.5 in 0.33 s, 25 60.3 in 0.95 s,
    /// 100 60.1 in 3.8 s (tinybvh's default is 25).
    std::uint32_t iterations = 25;
    /// Wall-clock budget in ms, checked between reinsertions; 0: none. A run stopped by it keeps
    /// what it did, so its tree depends on the machine's speed (the iteration bound does not).
    double time_budget_ms = 0;
    /// The share of the candidate nodes reinserted per batch, in (0, 1] (tinybvh's 1%).
    float batch_fraction = 0.01f;
    /// Merge subtrees of at most the tree's max_leaf_size primitives into one leaf where that is
    /// cheaper under the SAH (sah_cost's formula with the tree's C_trav and C_isect).
    bool merge_leaves = true;
};

/// Why an optimisation stopped.
enum class OptimizeStop {
    Converged,   ///< every node that may be taken out was, in vain
    Iterations,  ///< the batches asked for ran
    TimeBudget,  ///< the time budget ran out
};

/// What an optimisation did. SAH costs are sah_cost's (stats.h); sah_after <= sah_before always.
struct OptimizeStats {
    double sah_before = 0, sah_after = 0;
    std::uint32_t iterations = 0;     ///< batches run
    std::uint64_t attempts = 0;       ///< nodes taken out
    std::uint64_t reinsertions = 0;   ///< of them, the ones kept (the tree's cost went down)
    std::uint64_t leaves_merged = 0;  ///< subtrees merged into one leaf at the end
    double ms = 0;                    ///< wall time, conversions included
    OptimizeStop stop = OptimizeStop::Converged;
};

/// `tree` optimised as `config` says, as a new tree (`tree` untouched): a valid tree of the same
/// primitives, references and build settings (docs/design.md "Tree layout"), never of a higher
/// SAH cost. Single-threaded, so the result never depends on a thread count; the same tree and
/// config give the same tree unless the time budget stops it. `cancel` is polled between
/// reinsertions (its check may read `stats`, filled as the run goes); a stop throws Cancelled. Throws std::invalid_argument for a bad config.
Bvh optimized(const Bvh& tree, const OptimizeConfig& config, Cancellation* cancel = nullptr,
              OptimizeStats* stats = nullptr);

/// Throws std::invalid_argument naming the first setting out of range.
void validate(const OptimizeConfig& config);
std::string to_string(OptimizeStop stop);

}  // namespace bvhlab
