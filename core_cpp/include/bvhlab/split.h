// split.h — the contract between the top-down builder and the split methods (madmann91/bvh's
// shape: the builder owns the work stack; a split method only divides one range and says where).
//
// References live in two buffers of the same size. A split method reads a range from one
// (`src`) and either writes both children to the same range of the other (`dst`, a branch-free
// scatter: the fast way to partition) or reorders it in place; Split::buffer says which.
// A method never modifies `src` except when it succeeds in place, so a method can be tried on
// several axes without copies (split_best_of_axes).
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "bvhlab/build_config.h"
#include "bvhlab/cancel.h"
#include "bvhlab/prim_ref.h"
#include "bvhlab/sah.h"

namespace bvhlab {

class ThreadPool;

/// A half-open range [begin, end) of reference positions (the same in both buffers).
struct Range {
    std::uint32_t begin = 0, end = 0;
    std::uint32_t size() const { return end - begin; }
};

/// What the builder knows of a range: the box of its primitives, the box of their centroids,
/// and (for the methods that ask for it, see SplitMethodInfo) the sum of their centroids. The
/// binned SAH over all axes, which reads no centroid bounds, leaves the box in `centroids`
/// (a box that contains the centroids); the fallbacks that read it stay correct with that.
/// 16-byte aligned: copies inside Split and WorkItem then line up with the stores that wrote
/// it (split_common.cpp, write_bounds).
struct alignas(16) NodeBounds {
    Aabb box;
    Aabb centroids;
    double centroid_sum[3] = {0, 0, 0};
    bool has_sum = false;
    std::int32_t bins = -1;  ///< binned SAH: the BinStore slot its parent's pass filled, or -1
};

/// A split: positions [begin, mid) go left, [mid, end) right, both non-empty.
struct Split {
    std::uint32_t mid = 0;
    NodeBounds left, right;
    float cost = 0;           ///< SahCost::split of this split
    std::uint8_t buffer = 0;  ///< the buffer that now holds both children's references
    bool leaf = false;        ///< SahCost says a leaf is cheaper (only when SplitContext::leaf_allowed);
                              ///< nothing was moved then
};

class BinStore;  // binning.h

/// Per-thread memory the split methods may use (sized on first use, reused across nodes).
struct SplitScratch {
    SplitScratch();
    ~SplitScratch();
    std::vector<PrimRef> sorted;        ///< sweep SAH: the range sorted on one axis
    std::vector<PrimRef> merged;        ///< sweep SAH: the other side of a sort's merges (sort_in_chunks)
    std::vector<float> areas;           ///< sweep SAH suffix areas
    std::vector<std::uint32_t> counts;  ///< median: histogram
    std::vector<std::uint16_t> bucket;  ///< median: each reference's histogram bucket
    std::vector<std::uint64_t> ranks;   ///< median: (order key, position) of the candidates
    std::unique_ptr<BinStore> bins;     ///< binned SAH: buckets of the nodes on the work stack
};

/// The top of the tree is split with every thread working on the same node: a method cuts a large
/// range into chunks and runs its passes over them on the pool. Unset (nullptr) inside subtrees.
struct ParallelPasses {
    ThreadPool* pool = nullptr;
    unsigned threads = 1;
    const std::function<void()>* while_waiting = nullptr;  ///< the calling thread's cancellation check
    std::uint32_t root_size = 0;           ///< the root's range, [0, root_size): cut into chunks from kMinParallelRoot
    const Cancellation* cancel = nullptr;  ///< what while_waiting polls: a split may end its work early on a stop
};

struct SplitContext {
    PrimRef* buffers[2];
    const BuildConfig& config;
    SplitScratch& scratch;
    const ParallelPasses* parallel = nullptr;
    /// Set by the builder for each node: the range may be a leaf (a method that weighs leaves
    /// may answer Split::leaf), and the BinStore slots of the children's buckets are
    /// child_slot (right) and child_slot + 1 (left): the stack positions they will take.
    bool leaf_allowed = false;
    std::uint32_t child_slot = 0;
};

/// Ranges smaller than this are never cut into chunks, but the root.
inline constexpr std::uint32_t kMinParallelRange = 1u << 15;
/// The root is cut into chunks from two of the smallest (kMinParallelRange / 8): while it is split,
/// nothing else can run, where below it the pool splits the nodes too small to cut, one a task.
/// A root under 2^15 references was split by the calling thread alone (20K triangles, two threads:
/// 0.5 ms of a 3 ms build).
inline constexpr std::uint32_t kMinParallelRoot = kMinParallelRange / 4;
/// How many chunks a method cuts `r` into: several per thread at the top of the tree, else one.
std::uint32_t chunk_count(const SplitContext& ctx, Range r);
/// The k-th of `chunks` equal chunks of r.
Range chunk_of(Range r, std::uint32_t k, std::uint32_t chunks);
/// Runs pass(k, chunk_of(r, k, chunks)) for every chunk: on the pool when ctx.parallel is set.
void for_each_chunk(const SplitContext& ctx, Range r, std::uint32_t chunks,
                    const std::function<void(std::uint32_t, Range)>& pass);
/// Runs pass(k, ranges[k]) for every k, as for_each_chunk does, the largest ranges first.
void for_each_range(const SplitContext& ctx, std::span<const Range> ranges,
                    const std::function<void(std::uint32_t, Range)>& pass);

/// `axis` value asking a method to try every axis and keep the lowest SAH cost.
inline constexpr int kAllAxes = -1;

/// Splits the references of `r` held in buffer `src` on `axis` (or all axes with kAllAxes when
/// the method supports it). Returns nothing when this method cannot split the range (e.g. every
/// centroid lies on one side); the builder then falls back (see subtree_builder.cpp).
using SplitFunction = std::optional<Split> (*)(SplitContext&, Range, int src, const NodeBounds&, int axis);

std::optional<Split> split_median(SplitContext&, Range, int src, const NodeBounds&, int axis);
std::optional<Split> split_mean(SplitContext&, Range, int src, const NodeBounds&, int axis);
std::optional<Split> split_midpoint(SplitContext&, Range, int src, const NodeBounds&, int axis);
std::optional<Split> split_binned_sah(SplitContext&, Range, int src, const NodeBounds&, int axis);  // kAllAxes ok
std::optional<Split> split_sweep_sah(SplitContext&, Range, int src, const NodeBounds&, int axis);   // kAllAxes ok
std::optional<Split> split_lbvh(SplitContext&, Range, int src, const NodeBounds&, int axis);        // no axis

/// Everything the builder, the config parser, the stats and Python need to know about a split
/// method: the one table they all read (split_methods.cpp).
struct SplitMethodInfo {
    SplitMethod method;
    std::string_view name;  ///< as the Python API and the CLI spell it
    SplitFunction split;
    bool all_axes;              ///< takes kAllAxes itself (else split_best_of_axes tries each axis)
    bool uses_sah;              ///< weighs splits with SahCost, and so may stop early at a leaf
    bool needs_centroid_sum;    ///< reads NodeBounds::centroid_sum
    bool needs_morton_presort;  ///< the references are sorted by Morton code before the build
    bool bottom_up_boxes;       ///< splits without looking at bounds: node boxes are made from the
                                ///< leaves up after the build (NodeBounds stay empty meanwhile)
    bool binned;                ///< divides nodes into config.bins buckets over config.bin_bounds:
                                ///< the methods bins and bin_bounds apply to (the stats report
                                ///< them for these only)
};
std::span<const SplitMethodInfo> split_methods();
const SplitMethodInfo& method_info(SplitMethod method);

/// The SAH methods build ranges of at most small_subtree_size(config) references whole, with
/// the exact SAH (src/build/small_subtree.h), so their split functions only see larger ranges.
/// 32 since the small builder's sweep and sort lost a fifth of their instructions: against 24,
/// Sponza 42.8-43.6 against 43.1-43.6 ms median, room1m 186.3-188.6 against 187.7-190.0 ms,
/// uniform1m within noise (interleaved, one thread), each tree a little better (SAH 71.14 against
/// 71.25 on Sponza). 24 was the fastest before (Sponza 55.6 ms against 57.0 at 16, 56.6 at 20,
/// 56.5 at 28), 16 before the small builder's branches were removed.
inline constexpr std::uint32_t kSmallSubtree = 32;
/// The binned SAH over centroid bounds is the report's method (§2.3.2, Table 1): it bins every
/// range of more than this many, as it did before the small-subtree builder; ranges of at most
/// this many are split by the exact SAH of every position (small_subtree.h), where the report
/// binned them too: a departure from the report in its trees' last levels (at a node the exact
/// split is never dearer than a binned one, though the greedy tree as a whole need not be cheaper).
inline constexpr std::uint32_t kSmallExactReport = 8;
/// kSmallSubtree for the sweep SAH and the default binned SAH (buckets over the node's box),
/// kSmallExactReport for the binned SAH over centroid bounds, 0 for the other methods.
std::uint32_t small_subtree_size(const BuildConfig& config);

/// Runs `split` on each axis with a non-zero centroid extent and keeps the lowest-cost result
/// (the report's "try each axis", §2.3), for methods that do not evaluate all axes themselves.
std::optional<Split> split_best_of_axes(SplitFunction split, SplitContext&, Range, int src, const NodeBounds&);

/// Even split by index, in place: the fallback that always terminates.
Split split_even(SplitContext&, Range, int src, const NodeBounds&);

// ---- helpers shared by the split methods (split_common.cpp) ----

/// Box and centroid box of the references of r in buffer buf, and their centroid sum if asked for.
/// Sums are added in fixed blocks of the range, in order, so they do not depend on the threads.
NodeBounds bounds_of(const SplitContext&, Range r, int buf, bool with_centroid_sum);
/// The split at `mid` of a range already divided in buffer `buf`: both sides' bounds and the cost.
Split split_at(SplitContext&, Range, int buf, const NodeBounds& parent, std::uint32_t mid);

/// Partition on `centroid(axis) < position` into the other buffer; nothing if a side is empty.
std::optional<Split> split_at_position(SplitContext&, Range, int src, const NodeBounds& parent, int axis,
                                       float position);

}  // namespace bvhlab
