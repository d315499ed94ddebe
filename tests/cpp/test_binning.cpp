// The binned SAH's side test (binning.h): right_start() is the threshold below which a
// twice-centroid lies in buckets [0, last_left] of its frame. Checked against the bucket index
// (BinFrame::index, the definition) at the threshold, a few floats either side of it and at
// random points, over frames of very different sizes and places, every bucket count's boundaries.
// The buckets' counts (kept in a lane of the box, Bucket) stay exact on every instruction set
// path, up to the largest count a pass can reach, with denormals flushed or not.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "binning.h"
#include "bvhlab/isa.h"

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

namespace {

/// Bins 2 · n references into two copies of 8 buckets that start at `start` references each (a
/// copy of a pass holds at most half a build's 2^31 references), on the active path; checks that
/// every bucket counts exactly and that its box is the union of its references'.
void check_counts(std::uint32_t start, std::uint32_t n) {
    constexpr std::uint32_t kBins = 8;
    BinStore store(kBins);
    const BinSet copies[2] = {store.slot(0), store.slot(1)};
    const BinFrame frame(Aabb{{0, 0, 0}, {8, 8, 8}}, kBins);
    std::vector<PrimRef> refs(2 * n);
    std::vector<std::uint32_t> expected(3 * kBins, 0);
    for (std::uint32_t i = 0; i < refs.size(); ++i) {
        const float x = float(i % kBins), y = float((i / 3) % kBins), z = float((7 * i) % kBins);
        refs[i] = PrimRef{{x, y, z}, i, {x + 0.5f, y + 0.25f, z + 0.75f}, 0};
        ++expected[0 * kBins + std::uint32_t(x)], ++expected[1 * kBins + std::uint32_t(y)];
        ++expected[2 * kBins + std::uint32_t(z)];
    }
    for (const BinSet& copy : copies) {
        copy.reset();
        for (std::uint32_t k = 0; k < 3 * kBins; ++k) copy.bucket[k].set_count(start);
    }
    bin_refs(refs.data(), Range{0, std::uint32_t(refs.size())}, frame, copies);
    for (const BinSet& copy : copies) EXPECT_GE(copy.bucket[0].count(), start);  // before the merge
    copies[0].merge(copies[1]);
    for (int axis = 0; axis < 3; ++axis)
        for (std::uint32_t k = 0; k < kBins; ++k) {
            const std::uint32_t want = expected[axis * kBins + k];
            EXPECT_EQ(copies[0].count_of(axis, k, k + 1), 2 * start + want)
                << isa_name(active_isa()) << " axis " << axis << " bucket " << k << " from " << start;
            if (want == 0) continue;
            const Aabb box = copies[0].box_of(axis, k, k + 1);
            EXPECT_EQ(box.lo[axis], float(k)) << "axis " << axis << " bucket " << k;
            EXPECT_EQ(box.hi[axis] - box.lo[axis], axis == 0 ? 0.5f : axis == 1 ? 0.25f : 0.75f);
        }
}

/// Runs check_counts on every path this CPU has.
void check_counts_on_every_path() {
    const Isa before = active_isa();
    for (Isa isa : {Isa::Portable, Isa::Avx2}) {
        if (!isa_supported(isa)) continue;
        set_isa(isa);
        for (std::uint32_t start : {0u, 1u, (1u << 24) - 3u, (1u << 30) - 600u}) check_counts(start, 250);
    }
    set_isa(before);
}

}  // namespace

TEST(BinCounts, ExactUpToTheLargestCountOfACopy) { check_counts_on_every_path(); }

#if defined(__SSE__)
// Hosts may flush denormals (DAZ and FTZ in MXCSR: some render threads do): the counts' lane must
// not be read as one.
TEST(BinCounts, ExactWithDenormalsFlushed) {
    const unsigned saved = _mm_getcsr();
    _mm_setcsr(saved | 0x8040u);  // FTZ (bit 15) and DAZ (bit 6)
    check_counts_on_every_path();
    _mm_setcsr(saved);
}
#endif
