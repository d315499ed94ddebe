// split.h — the contract between the top-down builder and the split methods (STYLE.md: the
// builder owns the work stack; a split method only divides one range and says where).
//
// References live in two buffers of the same size. A split method reads a range from one
// (`src`) and either writes both children to the same range of the other (`dst`, a branch-free
// scatter: the fast way to partition) or reorders it in place; Split::buffer says which.
// A method never modifies `src` except when it succeeds in place, so a method can be tried on
// several axes without copies (split_best_of_axes).
#pragma once
#include <cstdint>
#include <optional>
#include <vector>
#include "bvhlab/build_config.h"
#include "bvhlab/prim_ref.h"

namespace bvhlab {

/// A half-open range [begin, end) of reference positions (the same in both buffers).
struct Range {
    std::uint32_t begin = 0, end = 0;
    std::uint32_t size() const { return end - begin; }
};

/// What the builder knows of a range: the box of its primitives, the box of their centroids,
/// and (for the mean split) the sum of their centroids when has_sum is set.
struct NodeBounds {
    Aabb box;
    Aabb centroids;
    double centroid_sum[3] = {0, 0, 0};
    bool has_sum = false;
};

/// A split: positions [begin, mid) go left, [mid, end) right, both non-empty.
struct Split {
    std::uint32_t mid = 0;
    NodeBounds left, right;
    float cost = 0;          ///< SAH cost of this split, C_trav + (A_L N_L + A_R N_R) / A_P · C_isect
    std::uint8_t buffer = 0; ///< the buffer that now holds both children's references
};

/// Per-thread memory the split methods may use (sized on first use, reused across nodes).
struct SplitScratch {
    std::vector<PrimRef> sorted;       ///< sweep SAH: the range sorted on one axis
    std::vector<float> areas;          ///< sweep SAH suffix areas
    std::vector<std::uint32_t> counts; ///< median: histogram
};

struct SplitContext {
    PrimRef* buffers[2];
    const BuildConfig& config;
    SplitScratch& scratch;
};

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

/// Ranges of at most this many references get the exact SAH from both SAH methods.
inline constexpr std::uint32_t kSmallExact = 16;
/// Exact SAH over every position of a small range (<= kSmallExact); kAllAxes ok.
std::optional<Split> split_small_exact(SplitContext&, Range, int src, const NodeBounds&, int axis);

/// Runs `split` on each axis with a non-zero centroid extent and keeps the lowest-cost result
/// (the report's "try each axis", §2.3), for methods that do not evaluate all axes themselves.
std::optional<Split> split_best_of_axes(SplitFunction split, SplitContext&, Range, int src, const NodeBounds&);

/// Even split by index, in place: the fallback that always terminates.
Split split_even(SplitContext&, Range, int src, const NodeBounds&);

// ---- helpers shared by the split methods (split_common.cpp) ----

/// Box and centroid box of n refs, and the centroid sum if asked for.
NodeBounds bounds_of(const PrimRef* refs, std::uint32_t n, bool with_centroid_sum = true);
/// SAH cost of splitting parent into (left, n_left) and (right, n_right).
inline float split_cost(const BuildConfig& config, const NodeBounds& parent, const Aabb& left,
                        std::uint32_t n_left, const Aabb& right, std::uint32_t n_right) {
    float parent_area = parent.box.half_area();
    float weighted = left.half_area() * float(n_left) + right.half_area() * float(n_right);
    // A box with no area (all primitives on a line or a point) gives no probabilities; count
    // every primitive as hit then, so splitting never looks cheaper than it is.
    float ratio = parent_area > 0.0f ? weighted / parent_area : float(n_left + n_right);
    return config.traversal_cost + ratio * config.intersection_cost;
}
/// The split at `mid` of a range already divided in buffer `buf`: both sides' bounds and the cost.
Split split_at(SplitContext&, Range, int buf, const NodeBounds& parent, std::uint32_t mid);

/// Branch-free partition of src[r] into dst[r]: references for which goes_left(p) holds fill
/// dst from r.begin forward, the others from r.end backward. Returns the first right position.
template <class GoesLeft>
std::uint32_t scatter_partition(const PrimRef* src, PrimRef* dst, Range r, GoesLeft&& goes_left) {
    std::uint32_t left = r.begin, right = r.end;
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        const PrimRef& p = src[i];
        // Select the slot with a mask, not a branch: at the top of the tree the side is a coin toss.
        const std::uint32_t l = goes_left(p) ? 1u : 0u;
        const std::uint32_t mask = 0u - l;
        dst[((right - 1) & ~mask) | (left & mask)] = p;
        left += l;
        right -= 1u - l;
    }
    return left;
}

/// Partition on `centroid(axis) < position` into the other buffer; nothing if a side is empty.
std::optional<Split> split_at_position(SplitContext&, Range, int src, const NodeBounds& parent, int axis,
                                       float position);

}  // namespace bvhlab
