// The binned SAH's side test (binning.h): right_start() is the threshold below which a
// twice-centroid lies in buckets [0, last_left] of its frame. Checked against the bucket index
// (BinFrame::index, the definition) at the threshold, a few floats either side of it and at
// random points, over frames of very different sizes and places, every bucket count's boundaries.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "binning.h"

using namespace bvhlab;

namespace {

/// Whether a reference with twice-centroid c2 on `axis` goes left, by its bucket.
bool left_by_bucket(const BinFrame& f, const BinSplit& s, float c2) { return f.index(c2, s.axis) <= s.last_left; }

void check_frame(const Aabb& box, std::uint32_t bins, int axis, std::mt19937& rng) {
    const BinFrame f(box, bins);
    ASSERT_TRUE(f.binned[axis]) << "the box must have an extent on the axis";
    std::uniform_real_distribution<float> along(2.0f * box.lo[axis], 2.0f * box.hi[axis]);
    for (std::uint32_t last_left = 0; last_left + 1 < bins; ++last_left) {
        const BinSplit s{0.0f, axis, last_left};
        const float at = right_start(f, s);
        ASSERT_TRUE(std::isfinite(at));
        EXPECT_FALSE(left_by_bucket(f, s, at)) << "bins " << bins << " last_left " << last_left;
        EXPECT_TRUE(left_by_bucket(f, s, std::nextafter(at, -INFINITY)))
            << "bins " << bins << " last_left " << last_left;
        float below = at, above = at;
        for (int k = 0; k < 4; ++k) {
            below = std::nextafter(below, -INFINITY), above = std::nextafter(above, INFINITY);
            EXPECT_TRUE(left_by_bucket(f, s, below));
            EXPECT_FALSE(left_by_bucket(f, s, above));
        }
        for (int k = 0; k < 64; ++k) {
            const float c2 = along(rng);
            EXPECT_EQ(c2 < at, left_by_bucket(f, s, c2)) << "c2 " << c2 << " threshold " << at;
        }
    }
}

}  // namespace

TEST(RightStart, IsWhereTheBucketIndexPassesTheSplit) {
    std::mt19937 rng(7);
    const float places[] = {0.0f, -1.0f, 3.5f, -1.0e6f, 7.0e7f};
    const float sizes[] = {1.0e-4f, 1.0f, 3.0f, 1234.5f, 1.0e7f};
    const std::uint32_t bin_counts[] = {2, 3, 8, 12, 31, 256};
    int frames = 0;
    for (float at : places)
        for (float size : sizes) {
            const Aabb box{{at, at - size, at + 0.5f * size}, {at + size, at, at + 1.5f * size}};
            for (int axis = 0; axis < 3; ++axis) {
                if (!(box.hi[axis] > box.lo[axis])) continue;  // a size below the place's float spacing
                for (std::uint32_t bins : bin_counts) check_frame(box, bins, axis, rng), ++frames;
            }
        }
    EXPECT_GE(frames, 380);
}

TEST(RightStart, BoxesWhoseBoundsAreOneFloatApart) {
    std::mt19937 rng(11);
    const float lo = 1.0f, hi = std::nextafter(lo, 2.0f);
    check_frame(Aabb{{lo, lo, lo}, {hi, hi, hi}}, 8, 1, rng);
}
