#include "sah_sweep.h"

#include "bvhlab/build_config.h"

namespace bvhlab {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

/// The union of the buckets seen so far on each axis, lane a holding axis a's: (lo, -hi) per
/// coordinate, grown by bucket j of the three axes (transposed so that lanes are axes).
struct AxisUnion {
    F4 lo[3] = {F4::splat(kInf), F4::splat(kInf), F4::splat(kInf)};
    F4 neg_hi[3] = {F4::splat(kInf), F4::splat(kInf), F4::splat(kInf)};
    std::uint32_t n[4] = {0, 0, 0, 0};

    void grow(const F4* box, const std::uint32_t* count, std::uint32_t bins, std::uint32_t j) {
        const F4* b0 = box + 2 * std::size_t(j);
        const F4* b1 = b0 + 2 * std::size_t(bins);
        const F4* b2 = b1 + 2 * std::size_t(bins);
        F4 t[3];
        transpose3(b0[0], b1[0], b2[0], b2[0], t[0], t[1], t[2]);
        for (int c = 0; c < 3; ++c) lo[c] = min(lo[c], t[c]);
        transpose3(b0[1], b1[1], b2[1], b2[1], t[0], t[1], t[2]);
        for (int c = 0; c < 3; ++c) neg_hi[c] = min(neg_hi[c], t[c]);
        for (int a = 0; a < 3; ++a) n[a] += count[std::size_t(a) * bins + j];
    }
    /// half_area of each lane's box, bit for bit (its operations in its order).
    F4 half_areas() const {
        const F4 zero = F4::splat(0.0f);
        const F4 x = max(neg(neg_hi[0]) - lo[0], zero), y = max(neg(neg_hi[1]) - lo[1], zero),
                 z = max(neg(neg_hi[2]) - lo[2], zero);
        return (x * y + y * z) + z * x;
    }
};

}  // namespace

AxisCuts cheapest_bin_cuts(const F4* box, const std::uint32_t* count, std::uint32_t bins, const SahCost& sah,
                           float inv_parent_area) {
    AxisCuts best;
    F4 right_area[kMaxBins];  // candidate c: the right side is buckets [c + 1, bins)
    std::uint32_t right_n[kMaxBins][4];
    AxisUnion u;
    for (std::uint32_t j = bins - 1; j > 0; --j) {
        u.grow(box, count, bins, j);
        right_area[j - 1] = u.half_areas();
        for (int a = 0; a < 4; ++a) right_n[j - 1][a] = u.n[a];
    }
    const F4 trav = F4::splat(sah.traversal), isect = F4::splat(sah.intersection), inv = F4::splat(inv_parent_area);
    u = AxisUnion();
    alignas(16) float cost[4];
    for (std::uint32_t c = 0; c + 1 < bins; ++c) {
        u.grow(box, count, bins, c);
        const F4 nl = F4::from_counts(u.n), nr = F4::from_counts(right_n[c]);
        F4 ratio;  // as SahCost::split
        if (inv_parent_area > 0.0f) {
            ratio = (u.half_areas() * nl + right_area[c] * nr) * inv;
        } else {
            std::uint32_t total[4];
            for (int a = 0; a < 4; ++a) total[a] = u.n[a] + right_n[c][a];
            ratio = F4::from_counts(total);
        }
        (trav + ratio * isect).store(cost);
        for (int a = 0; a < 3; ++a) {
            if (u.n[a] == 0 || right_n[c][a] == 0 || !(cost[a] < best.cost[a])) continue;
            best.cost[a] = cost[a], best.last_left[a] = c, best.found[a] = true;
        }
    }
    return best;
}

}  // namespace bvhlab
