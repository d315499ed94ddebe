// sah_sweep.h — the cheapest bucket boundary of the binned SAH (report §2.3.2) on the three axes
// at once: one vector lane per axis, one suffix and one prefix pass over the buckets (the O(B)
// sweep the report names as the improvement over its O(n + B²) loop). Small ranges sweep their
// sorted primitives the same way in small_subtree.cpp, with the same AxisBoxes and LaneSplitCost.
// With AVX2, both sweeps run sah_sweep_avx2.cpp's copies: the same operations, two boxes a step.
#pragma once
#include <cstdint>
#include <limits>

#include "bvhlab/prim_ref.h"
#include "bvhlab/sah.h"

namespace bvhlab {

inline constexpr float kSweepEmpty = std::numeric_limits<float>::infinity();

/// The boxes of the three axes' sweeps at once: box a, (lo[a], neg_hi[a]) in lanes x, y, z, is
/// axis a's. Growing is two `min`s per axis; half_areas() transposes only the three extents, so
/// that lane a of the areas is axis a's.
struct AxisBoxes {
    F4 lo[3] = {F4::splat(kSweepEmpty), F4::splat(kSweepEmpty), F4::splat(kSweepEmpty)};
    F4 neg_hi[3] = {F4::splat(kSweepEmpty), F4::splat(kSweepEmpty), F4::splat(kSweepEmpty)};

    /// Box a grows by (lo_a, neg_hi_a).
    void grow(F4 lo_0, F4 neg_hi_0, F4 lo_1, F4 neg_hi_1, F4 lo_2, F4 neg_hi_2) {
        lo[0] = min(lo[0], lo_0), neg_hi[0] = min(neg_hi[0], neg_hi_0);
        lo[1] = min(lo[1], lo_1), neg_hi[1] = min(neg_hi[1], neg_hi_1);
        lo[2] = min(lo[2], lo_2), neg_hi[2] = min(neg_hi[2], neg_hi_2);
    }
    /// half_area of each box, in lane a for box a, bit for bit (its operations in its order; the
    /// transpose only moves the extents).
    F4 half_areas() const {
        const F4 zero = F4::splat(0.0f);
        F4 x, y, z;
        transpose3(max(neg(neg_hi[0]) - lo[0], zero), max(neg(neg_hi[1]) - lo[1], zero),
                   max(neg(neg_hi[2]) - lo[2], zero), zero, x, y, z);
        return (x * y + y * z) + z * x;
    }
};

/// SahCost::split of each lane at once, bit for bit (its operations in its order), with one
/// parent's constants splatted once; the caller passes the counts as SahCost::counted has them.
class LaneSplitCost {
public:
    LaneSplitCost(const SahCost& sah, float inv_parent_area)
        : trav_(F4::splat(sah.traversal)),
          isect_(F4::splat(sah.intersection)),
          inv_(F4::splat(inv_parent_area)),
          by_area_(inv_parent_area > 0.0f) {}
    /// `total()`: n_left + n_right summed as integers (as counted), the ratio for a parent of zero
    /// area (only then called).
    template <class Total>
    F4 operator()(F4 left_area, F4 n_left, F4 right_area, F4 n_right, const Total& total) const {
        const F4 ratio = by_area_ ? (left_area * n_left + right_area * n_right) * inv_ : total();
        return trav_ + ratio * isect_;
    }

private:
    F4 trav_, isect_, inv_;
    bool by_area_;
};

/// The cheapest candidate of each lane and a key naming it, kept without branches (which
/// candidate wins is data, and a branch on it mispredicts). A strictly cheaper candidate replaces
/// the kept one, so ties keep the first; a lane that took none keeps kSweepEmpty.
struct LaneMin {
    F4 cost = F4::splat(kSweepEmpty), key = F4::splat(0.0f);

    void offer(F4 candidate, F4 key_of) { keep(less(candidate, cost), candidate, key_of); }
    /// Only in the lanes where `allowed` is set.
    void offer(F4 candidate, F4 key_of, F4 allowed) { keep(less(candidate, cost) & allowed, candidate, key_of); }

private:
    void keep(F4 taken, F4 candidate, F4 key_of) {
        cost = select(taken, candidate, cost), key = select(taken, key_of, key);
    }
};

/// Per axis, the cheapest boundary: buckets [0, last_left[a]] on the left. cost[a] is infinite
/// when no boundary leaves both sides non-empty.
struct AxisCuts {
    float cost[3] = {kSweepEmpty, kSweepEmpty, kSweepEmpty};
    std::uint32_t last_left[3] = {0, 0, 0};
};

struct Bucket;  // binning.h

/// The B = bins buckets of each axis, bucket k of axis a at bucket[a B + k] (BinSet's layout),
/// B in 2..kMaxBins. Every boundary is a candidate; a strictly cheaper one replaces the best so
/// far, so ties go to the first. Costs are SahCost::split's, bit for bit.
AxisCuts cheapest_bin_cuts(const Bucket* bucket, std::uint32_t bins, const SahCost& sah, float inv_parent_area);

}  // namespace bvhlab
