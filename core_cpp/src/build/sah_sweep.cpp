#include "sah_sweep.h"

#include "binning.h"

#include "bvhlab/build_config.h"
#include "bvhlab/isa.h"
#include "sah_sweep_avx2.h"

namespace bvhlab {
namespace {

/// The union of the buckets seen so far on each axis (AxisBoxes) and how many references they hold.
struct BucketUnion {
    AxisBoxes box;
    std::uint32_t n[4] = {0, 0, 0, 0};

    void grow(const Bucket* bucket, std::uint32_t bins, std::uint32_t j) {
        const Bucket &x = bucket[j], &y = bucket[bins + j],
                     &z = bucket[2 * std::size_t(bins) + j];  // bucket j of each axis
        box.grow(x.lo, x.neg_hi, y.lo, y.neg_hi, z.lo, z.neg_hi);
        n[0] += x.count(), n[1] += y.count(), n[2] += z.count();
    }
};

}  // namespace

AxisCuts cheapest_bin_cuts(const Bucket* bucket, std::uint32_t bins, const SahCost& sah, float inv_parent_area) {
    AxisCuts best;
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() >= Isa::Avx2) {
        std::uint32_t total = bucket[0].count();  // every reference of axis 0's buckets
        for (std::uint32_t j = 1; j < bins; ++j) total += bucket[j].count();
        alignas(16) float cost[4], last_left[4];
        avx2::bucket_sweep(bucket, bins, {sah.traversal, sah.intersection, inv_parent_area, sah.round_mask(total)},
                           cost, last_left);
        for (int a = 0; a < 3; ++a) best.cost[a] = cost[a], best.last_left[a] = std::uint32_t(last_left[a]);
        return best;
    }
#endif
    F4 right_area[kMaxBins];  // candidate c: the right side is buckets [c + 1, bins)
    std::uint32_t right_n[kMaxBins][4];
    BucketUnion u;
    for (std::uint32_t j = bins - 1; j > 0; --j) {
        u.grow(bucket, bins, j);
        right_area[j - 1] = u.box.half_areas();
        for (int a = 0; a < 4; ++a) right_n[j - 1][a] = u.n[a];
    }
    // the counts as the SAH counts them (SahCost::counted) under the parent, which holds every
    // reference of each axis's buckets
    const std::uint32_t mask = sah.round_mask(std::uint64_t(u.n[0]) + bucket[0].count());
    for (std::uint32_t j = 0; j + 1 < bins; ++j)
        for (int a = 0; a < 4; ++a) right_n[j][a] = SahCost::counted(right_n[j][a], mask);
    u = BucketUnion();
    const LaneSplitCost price(sah, inv_parent_area);
    const F4 zero = F4::splat(0.0f);
    LaneMin cheapest;  // per lane, among boundaries with both sides non-empty
    for (std::uint32_t c = 0; c + 1 < bins; ++c) {
        u.grow(bucket, bins, c);
        std::uint32_t left_n[4];
        for (int a = 0; a < 4; ++a) left_n[a] = SahCost::counted(u.n[a], mask);
        const auto total = [&] {
            std::uint32_t n[4];
            for (int a = 0; a < 4; ++a) n[a] = left_n[a] + right_n[c][a];
            return F4::from_counts(n);
        };
        const F4 n_left = F4::from_counts(left_n), n_right = F4::from_counts(right_n[c]);
        const F4 cost = price(u.box.half_areas(), n_left, right_area[c], n_right, total);
        cheapest.offer(cost, F4::splat(float(c)), less(zero, n_left) & less(zero, n_right));
    }
    std::uint32_t cut[4];
    truncate_to_u32(cheapest.key, cut);
    for (int a = 0; a < 3; ++a) best.cost[a] = cheapest.cost.lane(a), best.last_left[a] = cut[a];
    return best;
}

}  // namespace bvhlab
