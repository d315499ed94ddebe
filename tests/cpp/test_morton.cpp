// test_morton.cpp — the LBVH presort (src/build/morton.h) against its definition: every reference
// keeps its box, gets the Morton code of its centroid (interleaved here bit by bit), and the
// order is by code, ties in input order, on any number of threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "bvhlab/big_vector.h"
#include "bvhlab/cancel.h"
#include "morton.h"

namespace bvhlab {
namespace {

/// The code of quantized cell (x, y, z): bit i of x at 3i + 2, of y at 3i + 1, of z at 3i.
std::uint32_t interleave(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    std::uint32_t code = 0;
    for (int i = 0; i < 10; ++i)
        code |= ((x >> i) & 1u) << (3 * i + 2) | ((y >> i) & 1u) << (3 * i + 1) | ((z >> i) & 1u) << (3 * i);
    return code;
}

/// Points (boxes of no extent) on a grid, in random order: half of them in a small cluster (a few
/// large buckets of the top digit, many keys alike), the rest spread out (many buckets). With
/// `step`, the spread ones lie on a coarse grid: few distinct points, each a small bucket of
/// equal keys (the sort's insertion path).
BigVector<PrimRef> points(std::size_t n, std::uint32_t seed, int step = 1) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> wide(0, 2047 / step), narrow(0, 40);
    BigVector<PrimRef> refs(n);
    for (std::size_t i = 0; i < n; ++i) {
        float p[3];
        for (float& x : p) x = float(i % 2 ? wide(rng) * step : 600 + narrow(rng));
        refs[i] = PrimRef{{p[0], p[1], p[2]}, std::uint32_t(i), {p[0], p[1], p[2]}, 0};
    }
    return refs;
}

Aabb centroid_bounds(const BigVector<PrimRef>& refs) {
    Aabb b;
    for (const PrimRef& r : refs) b.grow(r.centroid());
    return b;
}

void expect_sorted_on_every_thread_count(const BigVector<PrimRef>& input) {
    const Aabb bounds = centroid_bounds(input);
    BigVector<PrimRef> one;
    for (unsigned threads : {1u, 2u, 3u, 4u}) {
        BigVector<PrimRef> refs = input;
        sort_by_morton_code(refs, bounds, threads, nullptr);
        ASSERT_EQ(refs.size(), input.size());
        std::vector<bool> seen(input.size(), false);
        for (std::size_t j = 0; j < refs.size(); ++j) {
            const PrimRef& r = refs[j];
            ASSERT_LT(r.ref, input.size());
            ASSERT_FALSE(seen[r.ref]) << "reference " << r.ref << " twice";
            seen[r.ref] = true;
            const PrimRef& was = input[r.ref];
            ASSERT_EQ(std::memcmp(r.lo, was.lo, sizeof r.lo), 0);
            ASSERT_EQ(std::memcmp(r.hi, was.hi, sizeof r.hi), 0);
            std::uint32_t q[3];
            for (int a = 0; a < 3; ++a) {  // 1024 cells over the extent, the top one closed
                const float scale = 1024.0f / (bounds.hi[a] - bounds.lo[a]);
                q[a] = std::uint32_t(std::min(1023.0f, std::floor((r.centroid(a) - bounds.lo[a]) * scale)));
            }
            ASSERT_EQ(r.code, interleave(q[0], q[1], q[2])) << "reference " << r.ref;
            if (j > 0) {
                const PrimRef& before = refs[j - 1];
                ASSERT_TRUE(before.code < r.code || (before.code == r.code && before.ref < r.ref))
                    << threads << " threads, position " << j;
            }
        }
        if (threads == 1) one = refs;
        else EXPECT_EQ(std::memcmp(refs.data(), one.data(), refs.size() * sizeof(PrimRef)), 0) << threads << " threads";
    }
}

TEST(Morton, SortedByCodeTiesInInputOrderOnEveryThreadCount) {
    expect_sorted_on_every_thread_count(points(300000, 5));  // several chunks of the passes (2^16 each)
    expect_sorted_on_every_thread_count(points(20000, 6, 256));
}

TEST(Morton, AStopLeavesTheReferencesAsTheyWere) {
    const BigVector<PrimRef> input = points(150000, 9);
    for (unsigned threads : {1u, 2u}) {
        BigVector<PrimRef> refs = input;
        Cancellation stop([] { return true; });
        sort_by_morton_code(refs, centroid_bounds(input), threads, &stop);
        EXPECT_TRUE(stop.stop_requested());
        EXPECT_EQ(std::memcmp(refs.data(), input.data(), refs.size() * sizeof(PrimRef)), 0) << threads << " threads";
    }
}

}  // namespace
}  // namespace bvhlab
