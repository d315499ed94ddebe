// sah_sweep.h — the cheapest bucket boundary of the binned SAH (report §2.3.2) on the three axes
// at once: one vector lane per axis, one suffix and one prefix pass over the buckets (the O(B)
// sweep the report names as the improvement over its O(n + B²) loop). Small ranges sweep their
// sorted primitives the same way in small_subtree.cpp.
#pragma once
#include <cstdint>
#include <limits>

#include "bvhlab/prim_ref.h"
#include "bvhlab/sah.h"

namespace bvhlab {

/// Per axis, the cheapest boundary: buckets [0, last_left[a]] on the left. found[a] is false
/// when no boundary leaves both sides non-empty.
struct AxisCuts {
    float cost[3] = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                     std::numeric_limits<float>::infinity()};
    std::uint32_t last_left[3] = {0, 0, 0};
    bool found[3] = {false, false, false};
};

/// The buckets of BinSet's layout: bucket k of axis a is box[2 (a B + k)] = lo and
/// box[2 (a B + k) + 1] = -hi, with count[a B + k] references; B = bins (2..kMaxBins).
/// Every boundary is a candidate; a strictly cheaper one replaces the best so far, so ties go to
/// the first. Costs are SahCost::split's, bit for bit.
AxisCuts cheapest_bin_cuts(const F4* box, const std::uint32_t* count, std::uint32_t bins, const SahCost& sah,
                           float inv_parent_area);

}  // namespace bvhlab
