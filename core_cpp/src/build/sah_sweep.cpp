#include "sah_sweep.h"

#include "bvhlab/build_config.h"

namespace bvhlab {
namespace {

/// The union of the buckets seen so far on each axis (AxisBoxes) and how many references they hold.
struct BucketUnion {
    AxisBoxes box;
    std::uint32_t n[4] = {0, 0, 0, 0};

    void grow(const F4* bucket, const std::uint32_t* count, std::uint32_t bins, std::uint32_t j) {
        const std::size_t i = 2 * std::size_t(j), axis = 2 * std::size_t(bins);  // bucket j of axes 0, 1, 2
        box.grow(bucket, bucket + 1, i, i + axis, i + 2 * axis);
        for (int a = 0; a < 3; ++a) n[a] += count[std::size_t(a) * bins + j];
    }
};

}  // namespace

AxisCuts cheapest_bin_cuts(const F4* box, const std::uint32_t* count, std::uint32_t bins, const SahCost& sah,
                           float inv_parent_area) {
    AxisCuts best;
    F4 right_area[kMaxBins];  // candidate c: the right side is buckets [c + 1, bins)
    std::uint32_t right_n[kMaxBins][4];
    BucketUnion u;
    for (std::uint32_t j = bins - 1; j > 0; --j) {
        u.grow(box, count, bins, j);
        right_area[j - 1] = u.box.half_areas();
        for (int a = 0; a < 4; ++a) right_n[j - 1][a] = u.n[a];
    }
    u = BucketUnion();
    const LaneSplitCost price(sah, inv_parent_area);
    alignas(16) float cost[4];
    for (std::uint32_t c = 0; c + 1 < bins; ++c) {
        u.grow(box, count, bins, c);
        const auto total = [&] {
            std::uint32_t n[4];
            for (int a = 0; a < 4; ++a) n[a] = u.n[a] + right_n[c][a];
            return F4::from_counts(n);
        };
        price(u.box.half_areas(), F4::from_counts(u.n), right_area[c], F4::from_counts(right_n[c]), total).store(cost);
        for (int a = 0; a < 3; ++a) {
            if (u.n[a] == 0 || right_n[c][a] == 0 || !(cost[a] < best.cost[a])) continue;
            best.cost[a] = cost[a], best.last_left[a] = c, best.found[a] = true;
        }
    }
    return best;
}

}  // namespace bvhlab
