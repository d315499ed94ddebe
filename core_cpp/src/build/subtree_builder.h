// subtree_builder.h — the one top-down builder (report §2.3): it owns the work stack, asks the
// configured split method where to split, and writes nodes in depth-first order.
#pragma once
#include <atomic>
#include <bit>
#include <cstdint>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/cancel.h"
#include "bvhlab/split.h"
#include "binning.h"

namespace bvhlab {

/// A range still to be turned into a subtree.
struct WorkItem {
    Range range;
    NodeBounds bounds;
    std::uint32_t parent = 0;  ///< node whose second-child index this item's node fills in
    std::uint32_t depth = 0;
    bool second_child = false;
    std::uint8_t buffer = 0;  ///< which of the two reference buffers holds the range
};

/// A range left to another thread: its placeholder node, its work item, and the buckets its
/// parent's pass filled for it (binned SAH; else empty), which the thread that builds it adopts
/// (adopt_bins) rather than binning the range again.
struct DeferredRange {
    std::uint32_t node = 0;
    WorkItem item;
    std::vector<Bucket> bins;
};

/// Nodes of one subtree in depth-first order, and the ranges it left for other threads.
struct Subtree {
    BigVector<BvhNode> nodes;
    BigVector<std::uint8_t> depths;
    std::vector<DeferredRange> deferred;
    std::vector<Range> unpacked;  ///< leaf positions whose geometry is packed after (BuildShared::prims)
    std::vector<Subtree> parts;   ///< once built: the subtree of each deferred range, in its order (assemble)
};

/// State shared by every thread of one build.
struct BuildShared {
    PrimRef* buffers[2];       ///< ping-pong reference buffers (split.h)
    std::uint32_t* leaf_refs;  ///< output: the references in leaf order
    const BuildConfig& config;
    const SplitMethodInfo& method;
    Cancellation& cancel;                              ///< workers read stop_requested(); the calling thread polls it
    std::atomic<std::uint64_t>& primitives_in_leaves;  ///< progress: primitives placed in leaves
    /// Where the build packs the leaves' geometry (Bvh::prims, in leaf order), or null when it is
    /// packed after the build (pack_prims): set where the small-subtree builder makes most leaves.
    /// A small subtree whose input lies close together fetches it when it starts and packs each
    /// leaf as it is made; the other leaves are listed in Subtree::unpacked and packed in runs
    /// afterwards (pack_unpacked), as input visited at random is packed faster in one stream.
    const GeometryView* geometry = nullptr;
    PackedPrim* prims = nullptr;
};

/// Packs the geometry of `subtree`'s unpacked ranges (BuildShared::prims).
void pack_unpacked(const BuildShared& shared, const Subtree& subtree);

/// How one call of build_subtree runs: on the calling thread (which polls the cancellation and
/// may cut large ranges into chunks for the pool) or on a worker.
struct SubtreeRun {
    std::uint32_t defer_size = 0;  ///< ranges of at most this many (but the root) are deferred; 0: none
    bool calling_thread = false;
    const ParallelPasses* parallel = nullptr;  ///< data-parallel passes for large ranges
    /// Ranges (but the root) smaller than this are deferred too, whatever their size against
    /// defer_size: at the top of a build on several threads, the ranges that no pass cuts into
    /// chunks (kMinParallelRange), which the calling thread would otherwise split alone while
    /// the other threads wait. 0: none.
    std::uint32_t serial_below = 0;
};

/// Builds the subtree of `root` into `out`. Deferred ranges are left in out.deferred as
/// placeholder nodes. Returns early (with an unfinished subtree) when the build is cancelled.
void build_subtree(BuildShared& shared, SplitScratch& scratch, const WorkItem& root, Subtree& out,
                   const SubtreeRun& run);

/// Decides a node: true and the split to make written to `out`, or false for a leaf.
bool choose_split(SplitContext& ctx, const WorkItem& item, Split& out);

/// The axis policy (report §2.3) for a node with this centroid extent, range and depth, or
/// kAllAxes. Random hashes the node's own range and depth, not a shared generator, so the tree
/// is the same whichever thread builds which subtree.
int choose_axis(const BuildConfig& cfg, Vec3 centroid_extent, Range range, std::uint32_t depth);

/// Median splits keep every leaf within depth + ceil(log2 n) (report §3.1: the GPU stack is
/// MAX_TREE_HEIGHT deep), so once a branch could outgrow that, it continues with them.
/// Inline: the small-subtree builder asks it at every node.
inline bool too_deep(std::uint32_t depth, std::uint32_t n) {
    const std::uint32_t median_height = std::bit_width(n - 1);  // ceil(log2 n) for n >= 1
    return depth + median_height >= gpu::MAX_TREE_HEIGHT - 1;
}

}  // namespace bvhlab
