// The binned SAH's O(B) sweep (sah_sweep.h cheapest_bin_cuts, three axes in vector lanes) against
// the scalar definition, SahCost::split, evaluated at every bucket boundary from the buckets'
// own boxes and counts: the same cheapest cost bit for bit and the same boundary, for bucket
// counts 2 to 256, SAH blocks 1 to 64 (sah.h: counts rounded up to whole blocks above a node of
// one block), other SAH costs, and parents of zero area (every reference at one point, or on a line).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "binning.h"
#include "sah_sweep.h"

using namespace bvhlab;

namespace {

float half_area_of(const float lo[3], const float hi[3]) {
    float e[3];
    for (int a = 0; a < 3; ++a) e[a] = std::max(hi[a] - lo[a], 0.0f);
    return (e[0] * e[1] + e[1] * e[2]) + e[2] * e[0];
}

std::uint32_t bits_of(float x) {
    std::uint32_t b;
    std::memcpy(&b, &x, sizeof(b));
    return b;
}

/// The cheapest boundary of `axis` by SahCost::split at each one (ties to the first): the cost
/// and the last bucket on the left; an infinite cost when no boundary leaves both sides non-empty.
std::pair<float, std::uint32_t> scalar_cut(const std::vector<Bucket>& bucket, std::uint32_t bins, int axis,
                                           const SahCost& sah, float inv) {
    float best = INFINITY;
    std::uint32_t best_cut = 0;
    for (std::uint32_t c = 0; c + 1 < bins; ++c) {
        float lo[2][3], hi[2][3];
        std::uint32_t n[2] = {0, 0};
        for (int s = 0; s < 2; ++s)
            for (int x = 0; x < 3; ++x) lo[s][x] = INFINITY, hi[s][x] = -INFINITY;
        for (std::uint32_t k = 0; k < bins; ++k) {
            const Bucket& b = bucket[axis * bins + k];
            if (!b.count()) continue;
            const int side = k <= c ? 0 : 1;
            n[side] += b.count();
            for (int x = 0; x < 3; ++x)
                lo[side][x] = std::min(lo[side][x], b.lo.lane(x)),
                hi[side][x] = std::max(hi[side][x], -b.neg_hi.lane(x));
        }
        if (!n[0] || !n[1]) continue;
        const float cost = sah.split(inv, half_area_of(lo[0], hi[0]), n[0], half_area_of(lo[1], hi[1]), n[1]);
        if (cost < best) best = cost, best_cut = c;
    }
    return {best, best_cut};
}

}  // namespace

TEST(CheapestBinCuts, IsSahCostSplitAtEveryBoundaryBitForBit) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> place(0.0f, 10.0f);
    const std::uint32_t bin_counts[] = {2, 3, 4, 8, 13, 32, 256};
    int checked = 0, found = 0;
    for (int round = 0; round < 6000; ++round) {
        const std::uint32_t bins = bin_counts[rng() % 7], block = 1u << (rng() % 7);
        const std::uint32_t references = 2 + rng() % (rng() % 2 ? 12 : 300);
        const int kind = int(rng() % 4);  // 0 boxes anywhere, 1 one point, 2 a line, 3 the end buckets only
        std::vector<Bucket> bucket(3 * bins);
        for (Bucket& b : bucket) b = Bucket::empty();
        float parent_lo[3] = {INFINITY, INFINITY, INFINITY}, parent_hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (std::uint32_t i = 0; i < references; ++i) {
            float lo[4] = {place(rng), place(rng), place(rng), 0.0f}, hi[4] = {0.0f, 0.0f, 0.0f, 0.0f};
            for (int a = 0; a < 3; ++a) hi[a] = lo[a] + 0.1f * place(rng);
            if (kind == 1)
                for (int a = 0; a < 3; ++a) lo[a] = hi[a] = 1.0f;  // every reference at one point
            if (kind == 2)
                for (int a = 1; a < 3; ++a) lo[a] = hi[a] = 1.0f;  // on a line along x
            for (int a = 0; a < 3; ++a)
                parent_lo[a] = std::min(parent_lo[a], lo[a]), parent_hi[a] = std::max(parent_hi[a], hi[a]);
            for (int a = 0; a < 3; ++a) {  // every reference is in one bucket of each axis
                const std::uint32_t k = kind == 3 ? (rng() % 2) * (bins - 1) : std::uint32_t(rng() % bins);
                bucket[a * bins + k].add(F4::load(lo), neg(F4::load(hi)));
            }
        }
        BuildConfig config;
        config.sah_block = block;
        if (rng() % 3 == 0) config.traversal_cost = 0.3f, config.intersection_cost = 1.7f;
        const SahCost sah(config);
        const float inv = SahCost::inverse_area(half_area_of(parent_lo, parent_hi));
        const AxisCuts cuts = cheapest_bin_cuts(bucket.data(), bins, sah, inv);
        for (int a = 0; a < 3; ++a) {
            const auto [cost, cut] = scalar_cut(bucket, bins, a, sah, inv);
            EXPECT_EQ(bits_of(cost), bits_of(cuts.cost[a]))
                << "round " << round << " bins " << bins << " block " << block << " kind " << kind << " axis " << a;
            if (std::isfinite(cost)) {
                EXPECT_EQ(cut, cuts.last_left[a]) << "round " << round << " axis " << a;
                ++found;
            }
            ++checked;
        }
    }
    EXPECT_EQ(checked, 18000);
    EXPECT_GT(found, 9000);
}
