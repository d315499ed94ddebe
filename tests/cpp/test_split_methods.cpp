// The median, mean and midpoint splits of one range against brute force (report §2.3.1): which
// references go left, in which order, the sides' bounds, on hostile inputs (every centroid equal,
// duplicates, signed zeros, huge and tiny coordinates together), on every instruction set path
// and with the range cut into chunks on a pool.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

#include "bvhlab/isa.h"
#include "bvhlab/split.h"
#include "bvhlab/thread_pool.h"

using namespace bvhlab;

namespace {

/// The references of one range in two buffers, and what a split method needs to run on them.
struct Fixture {
    std::vector<PrimRef> buffers[2];
    BuildConfig config;
    SplitScratch scratch;
    std::uint32_t begin;

    Fixture(const std::vector<Aabb>& boxes, std::uint32_t offset, SplitMethod method) : begin(offset) {
        config.method = method;
        for (auto& b : buffers) b.resize(offset + boxes.size() + 3);  // something before and after the range
        for (std::size_t i = 0; i < boxes.size(); ++i) {
            PrimRef& p = buffers[0][offset + i];
            p = {{boxes[i].lo.x, boxes[i].lo.y, boxes[i].lo.z},
                 std::uint32_t(i),
                 {boxes[i].hi.x, boxes[i].hi.y, boxes[i].hi.z},
                 0};
        }
    }
    Range range() const { return {begin, begin + std::uint32_t(buffers[0].size() - begin - 3)}; }
    SplitContext context(const ParallelPasses* parallel) {
        return {{buffers[0].data(), buffers[1].data()}, config, scratch, parallel};
    }
};

float twice_centroid(const Aabb& b, int axis) { return b.lo[axis] + b.hi[axis]; }

Aabb box_of(const std::vector<Aabb>& boxes, const std::vector<std::uint32_t>& ids) {
    Aabb a;
    for (std::uint32_t i : ids) a.grow(boxes[i]);
    return a;
}

bool same_box(const Aabb& a, const Aabb& b) {
    for (int k = 0; k < 3; ++k)
        if (a.lo[k] != b.lo[k] || a.hi[k] != b.hi[k]) return false;
    return true;
}

/// Runs the median split and checks it against a stable sort on (twice-centroid, position).
std::vector<PrimRef> check_median(const std::vector<Aabb>& boxes, int axis, std::uint32_t offset,
                                  const ParallelPasses* parallel = nullptr) {
    Fixture f(boxes, offset, SplitMethod::Median);
    SplitContext ctx = f.context(parallel);
    const Range r = f.range();
    const NodeBounds b = bounds_of(ctx, r, 0, false);
    const std::optional<Split> s = split_median(ctx, r, 0, b, axis);
    const std::uint32_t n = r.size();
    EXPECT_TRUE(s.has_value());
    if (!s) return {};
    EXPECT_EQ(s->mid, r.begin + n / 2);

    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) {
        return twice_centroid(boxes[p], axis) < twice_centroid(boxes[q], axis);
    });
    std::vector<std::uint32_t> left(order.begin(), order.begin() + n / 2), right(order.begin() + n / 2, order.end());
    std::sort(left.begin(), left.end()), std::sort(right.begin(), right.end());

    const std::vector<PrimRef>& out = f.buffers[s->buffer];
    std::vector<std::uint32_t> got_left, got_right;
    for (std::uint32_t i = r.begin; i < s->mid; ++i) got_left.push_back(out[i].ref);
    for (std::uint32_t i = r.end; i-- > s->mid;) got_right.push_back(out[i].ref);
    EXPECT_EQ(got_left, left) << "left: the first n/2 in (centroid, position) order, in input order";
    EXPECT_EQ(got_right, right) << "right: the rest, in input order from the end";
    if (!left.empty() && !right.empty()) {
        float left_max = -INFINITY, right_min = INFINITY;
        for (std::uint32_t i : left) left_max = std::max(left_max, twice_centroid(boxes[i], axis));
        for (std::uint32_t i : right) right_min = std::min(right_min, twice_centroid(boxes[i], axis));
        EXPECT_LE(left_max, right_min);
    }
    EXPECT_TRUE(same_box(s->left.box, box_of(boxes, left)));
    EXPECT_TRUE(same_box(s->right.box, box_of(boxes, right)));
    return out;
}

std::vector<Aabb> random_boxes(std::size_t n, std::uint32_t seed, float spread, int distinct = 0) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-spread, spread), size(0.0f, 1.0f);
    std::uniform_int_distribution<int> pick(0, std::max(distinct, 1) - 1);
    std::vector<Aabb> boxes(n);
    for (Aabb& b : boxes) {
        const Vec3 c =
            distinct ? Vec3{float(pick(rng)), float(pick(rng)), float(pick(rng))} : Vec3{u(rng), u(rng), u(rng)};
        const float h = distinct ? 0.5f : size(rng);
        b = {{c.x - h, c.y - h, c.z - h}, {c.x + h, c.y + h, c.z + h}};
    }
    return boxes;
}

/// Every path this build and CPU offer, each checked, all giving the same output.
void check_median_on_every_path(const std::vector<Aabb>& boxes, int axis, std::uint32_t offset = 5) {
    const Isa before = active_isa();
    std::vector<PrimRef> first;
    for (Isa isa : {Isa::Portable, Isa::Avx2}) {
        if (!isa_supported(isa)) continue;
        set_isa(isa);
        std::vector<PrimRef> out = check_median(boxes, axis, offset);
        if (first.empty()) first = out;
        EXPECT_EQ(0, std::memcmp(first.data(), out.data(), out.size() * sizeof(PrimRef))) << isa_name(isa);
    }
    set_isa(before);
}

TEST(MedianSplit, MatchesAStableSortAroundTheThresholds) {
    for (std::size_t n : {3, 4, 17, 127, 128, 129, 1000, 4097, 20001})
        for (int axis = 0; axis < 3; ++axis)
            check_median_on_every_path(random_boxes(n, std::uint32_t(n) + axis, 100.0f), axis);
}

TEST(MedianSplit, AllCentroidsEqualSplitsByPosition) {
    for (std::size_t n : {5, 200, 3001}) {
        std::vector<Aabb> boxes(n);
        for (std::size_t i = 0; i < n; ++i) {  // same centroid, different boxes
            const float h = 1.0f + float(i % 7);
            boxes[i] = {{-h, 2.0f - h, 3.0f - h}, {h, 2.0f + h, 3.0f + h}};
        }
        boxes[0] = {{-1, 0, 0}, {1, 4, 7}};  // one other centroid on y and z: a non-zero extent there
        check_median_on_every_path(boxes, 0);
    }
}

TEST(MedianSplit, DuplicatesAndSignedZeros) {
    check_median_on_every_path(random_boxes(5000, 9, 0.0f, 3), 1);  // three distinct centroids per axis
    std::vector<Aabb> boxes = random_boxes(700, 10, 1.0f);
    for (std::size_t i = 0; i < boxes.size(); i += 3) boxes[i] = {{-0.0f, -0.0f, -0.0f}, {-0.0f, -0.0f, -0.0f}};
    for (std::size_t i = 1; i < boxes.size(); i += 3) boxes[i] = {{-1.0f, -1.0f, -1.0f}, {1.0f, 1.0f, 1.0f}};  // +0
    for (int axis = 0; axis < 3; ++axis) check_median_on_every_path(boxes, axis);
}

TEST(MedianSplit, HugeAndTinyCoordinatesTogether) {
    std::vector<Aabb> boxes = random_boxes(3000, 11, 1.0f);
    for (std::size_t i = 0; i < boxes.size(); i += 5) {
        const float s = (i % 2 ? 1e30f : -1e30f) / float(i + 1);
        boxes[i] = {{s, s, s}, {s, s, s}};
    }
    for (std::size_t i = 2; i < boxes.size(); i += 7) boxes[i] = {{1e-38f, 0, 0}, {3e-38f, 1e-40f, 0}};
    for (int axis = 0; axis < 3; ++axis) check_median_on_every_path(boxes, axis);
}

TEST(MedianSplit, ChunksOnAPoolGiveTheSameOutput) {
    const std::vector<Aabb> boxes = random_boxes(100000, 12, 50.0f, 40);
    const std::vector<PrimRef> alone = check_median(boxes, 2, 7);
    ThreadPool pool(3);
    const ParallelPasses parallel{&pool, 4, nullptr};
    const std::vector<PrimRef> chunked = check_median(boxes, 2, 7, &parallel);
    EXPECT_EQ(0, std::memcmp(alone.data(), chunked.data(), alone.size() * sizeof(PrimRef)));
}

/// Mean and midpoint: left holds exactly the centroids below the position, each side's bounds
/// and (for the mean) centroid sums are those of its references.
void check_position_split(SplitMethod method, const std::vector<Aabb>& boxes, const ParallelPasses* parallel) {
    Fixture f(boxes, 3, method);
    SplitContext ctx = f.context(parallel);
    const Range r = f.range();
    const bool sums = method == SplitMethod::Mean;
    const NodeBounds b = bounds_of(ctx, r, 0, sums);
    const int axis = largest_axis(b.centroids.extent());
    long double total = 0;
    for (const Aabb& box : boxes) total += 0.5L * twice_centroid(box, axis);
    const float position = sums ? float(b.centroid_sum[axis] / double(boxes.size()))
                                : 0.5f * (b.centroids.lo[axis] + b.centroids.hi[axis]);
    if (sums) EXPECT_NEAR(b.centroid_sum[axis], double(total), 1e-12 * std::abs(double(total)) + 1e-9);
    const std::optional<Split> s = (sums ? split_mean : split_midpoint)(ctx, r, 0, b, axis);
    ASSERT_TRUE(s.has_value());
    std::vector<std::uint32_t> left, right;
    for (std::uint32_t i = 0; i < boxes.size(); ++i)
        (twice_centroid(boxes[i], axis) < 2.0f * position ? left : right).push_back(i);
    ASSERT_EQ(s->mid - r.begin, left.size());
    const std::vector<PrimRef>& out = f.buffers[s->buffer];
    for (std::uint32_t i = r.begin; i < s->mid; ++i) EXPECT_EQ(out[i].ref, left[i - r.begin]);
    EXPECT_TRUE(same_box(s->left.box, box_of(boxes, left)));
    EXPECT_TRUE(same_box(s->right.box, box_of(boxes, right)));
    if (sums) {
        long double left_sum = 0;
        for (std::uint32_t i : left) left_sum += 0.5L * twice_centroid(boxes[i], axis);
        EXPECT_NEAR(s->left.centroid_sum[axis], double(left_sum), 1e-12 * std::abs(double(total)) + 1e-9);
    }
}

TEST(PositionSplits, LeftHoldsTheCentroidsBelowThePosition) {
    ThreadPool pool(3);
    const ParallelPasses parallel{&pool, 4, nullptr};
    for (SplitMethod m : {SplitMethod::Mean, SplitMethod::Midpoint})
        for (std::size_t n : {2, 9, 4096, 4097, 70000}) {
            check_position_split(m, random_boxes(n, std::uint32_t(n), 30.0f), nullptr);
            if (n > 100) check_position_split(m, random_boxes(n, std::uint32_t(n), 30.0f, 5), &parallel);
        }
}

}  // namespace

TEST(SplitMethodTable, TheBinnedMethodsAreThoseOfTheBinnedSahSplit) {
    int binned = 0;
    for (const SplitMethodInfo& m : split_methods()) {
        EXPECT_EQ(m.binned, m.split == split_binned_sah) << m.name;
        binned += m.binned;
    }
    EXPECT_EQ(binned, 2);  // sah and sbvh
}
