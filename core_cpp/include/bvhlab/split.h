// split.h — the contract between the top-down builder and the split methods (STYLE.md: the
// builder owns the work stack; a split method only partitions one range and says where).
#pragma once
#include <cstdint>
#include <optional>
#include <vector>
#include "bvhlab/build_config.h"
#include "bvhlab/prim_ref.h"

namespace bvhlab {

/// A half-open range [begin, end) of the PrimRef array.
struct Range {
    std::uint32_t begin = 0, end = 0;
    std::uint32_t size() const { return end - begin; }
};

/// What the builder knows of a range: the box of its primitives and the box of their centroids.
struct NodeBounds {
    Aabb box;
    Aabb centroids;
};

/// A split of a range: [begin, mid) goes left, [mid, end) right, both non-empty.
struct Split {
    std::uint32_t mid = 0;
    NodeBounds left, right;
    float cost = 0;  ///< SAH cost of this split, C_trav + (A_L N_L + A_R N_R) / A_P · C_isect
};

/// Per-thread memory the split methods may use (sized on first use, reused across nodes).
struct SplitScratch {
    std::vector<PrimRef> original, best;  ///< best-of-three-axes trials
    std::vector<float> areas;             ///< sweep SAH suffix areas
};

struct SplitContext {
    PrimRef* refs;
    const BuildConfig& config;
    SplitScratch& scratch;
};

/// `axis` value asking a method to try every axis and keep the lowest SAH cost.
inline constexpr int kAllAxes = -1;

/// Partitions refs[range] on `axis` (or all axes with kAllAxes when the method supports it) and
/// returns the split, or nothing when this method cannot split the range (e.g. every centroid
/// lies on one side); the builder then falls back (see builder.cpp).
using SplitFunction = std::optional<Split> (*)(SplitContext&, Range, const NodeBounds&, int axis);

std::optional<Split> split_median(SplitContext&, Range, const NodeBounds&, int axis);
std::optional<Split> split_mean(SplitContext&, Range, const NodeBounds&, int axis);
std::optional<Split> split_midpoint(SplitContext&, Range, const NodeBounds&, int axis);
std::optional<Split> split_binned_sah(SplitContext&, Range, const NodeBounds&, int axis);  // kAllAxes ok
std::optional<Split> split_sweep_sah(SplitContext&, Range, const NodeBounds&, int axis);   // kAllAxes ok
std::optional<Split> split_lbvh(SplitContext&, Range, const NodeBounds&, int axis);        // axis unused

/// Runs `split` on each axis with a non-zero centroid extent and keeps the lowest-cost result
/// (the report's "try each axis", §2.3), for methods that do not evaluate all axes themselves.
std::optional<Split> split_best_of_axes(SplitFunction split, SplitContext&, Range, const NodeBounds&);

/// Even split by index, no reordering: the fallback that always terminates.
Split split_even(SplitContext&, Range, const NodeBounds&);

// ---- helpers shared by the split methods (split_common.cpp) ----

/// Box and centroid box of n refs.
NodeBounds bounds_of(const PrimRef* refs, std::uint32_t n);
/// SAH cost of splitting parent into (left, n_left) and (right, n_right).
float split_cost(const BuildConfig& config, const NodeBounds& parent, const Aabb& left,
                 std::uint32_t n_left, const Aabb& right, std::uint32_t n_right);
/// The split at `mid` of an already ordered range: computes both sides' bounds and the cost.
Split split_at(SplitContext&, Range, const NodeBounds& parent, std::uint32_t mid);
/// Partition on `centroid(axis) < position`, returning nothing if a side would be empty.
std::optional<Split> split_at_position(SplitContext&, Range, const NodeBounds& parent, int axis, float position);

}  // namespace bvhlab
