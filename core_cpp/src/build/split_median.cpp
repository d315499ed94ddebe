// Median split (report §2.3.1, PBRT "EqualCounts"): the ⌊n/2⌋ references first in the order
// (twice-centroid on the axis, position in the range) go left, in O(n) — never a sort. The
// order is total, so ties between equal centroids are broken by position and the split is the
// same on every path. A histogram of the centroids finds the bucket that holds the median; only
// that bucket's references are ranked exactly (std::nth_element, the report's
// select_nth_unstable, on 8-byte keys rather than 32-byte references); one branch-free scatter
// then moves every reference once, each side in input order, and the sides' bounds follow.
#include <algorithm>
#include <bit>
#include <cmath>

#include "bvhlab/split.h"
#include "partition.h"

namespace bvhlab {
namespace {

/// Ranges smaller than this rank every reference; a histogram would cost more than it saves.
constexpr std::uint32_t kDirectSelect = 128;

/// An unsigned key in the order of the floats (-0 taken as +0, as `<` and `==` take it).
std::uint64_t order_key(float x) {
    const auto bits = std::bit_cast<std::uint32_t>(x + 0.0f);
    return bits ^ (std::uint32_t(std::int32_t(bits) >> 31) | 0x80000000u);
}
float from_order_key(std::uint32_t key) { return std::bit_cast<float>(key & 0x80000000u ? key ^ 0x80000000u : ~key); }

/// The rank key of the reference at offset i of the range: twice-centroid first, then i.
std::uint64_t rank_key(const PrimRef& p, int axis, std::uint32_t i) {
    return order_key(p.lo[axis] + p.hi[axis]) << 32 | i;
}

struct Bucketer {
    float origin, scale, top;
    int axis;
    std::uint32_t operator()(const PrimRef& p) const {
        return truncate_clamped(((p.lo[axis] + p.hi[axis]) - origin) * scale, top);  // on 2·centroid
    }
};

/// The rank keys that may hold the median, and how many references rank below all of them.
std::uint32_t median_candidates(SplitContext& ctx, const PrimRef* in, Range r, const NodeBounds& b, int axis) {
    auto& ranks = ctx.scratch.ranks;
    ranks.clear();
    if (r.size() < kDirectSelect) {
        for (std::uint32_t i = r.begin; i < r.end; ++i) ranks.push_back(rank_key(in[i], axis, i - r.begin));
        return 0;
    }
    const std::uint32_t buckets = std::min<std::uint32_t>(1024, r.size() / 16);
    const float extent = b.centroids.extent()[axis];
    const float scale = extent > 0 ? float(buckets) / (2.0f * extent) : 0.0f;
    const Bucketer bucket{2.0f * b.centroids.lo[axis], std::isfinite(scale) ? scale : 0.0f, float(buckets - 1), axis};
    auto& count = ctx.scratch.counts;
    auto& of = ctx.scratch.bucket;
    count.assign(buckets, 0);
    of.resize(r.size());
    for (std::uint32_t i = r.begin; i < r.end; ++i) ++count[of[i - r.begin] = std::uint16_t(bucket(in[i]))];
    // the bucket holding the median (the bucketing is monotone in the centroid)
    const std::uint32_t half = r.size() / 2;
    std::uint32_t median_bucket = 0, below = 0;
    while (below + count[median_bucket] <= half) below += count[median_bucket++];
    for (std::uint32_t i = 0; i < r.size(); ++i)
        if (of[i] == median_bucket) ranks.push_back(rank_key(in[r.begin + i], axis, i));
    return below;
}

}  // namespace

std::optional<Split> split_median(SplitContext& ctx, Range r, int src, const NodeBounds& b, int axis) {
    const PrimRef* in = ctx.buffers[src];
    PrimRef* out = ctx.buffers[1 - src];
    const std::uint32_t below = median_candidates(ctx, in, r, b, axis);
    auto& ranks = ctx.scratch.ranks;
    const auto nth = ranks.begin() + (r.size() / 2 - below);
    std::nth_element(ranks.begin(), nth, ranks.end());
    const RankPivot pivot{axis, from_order_key(std::uint32_t(*nth >> 32)), r.begin, std::uint32_t(*nth)};
    auto run = [&](Range c, std::uint32_t left, std::uint32_t right, bool contained) {
        return scatter_ranked(in, out, c, left, right, pivot, contained);
    };
    const std::uint32_t mid = partition_with(ctx, r, in, BeforePivot{pivot}, run);
    return split_at(ctx, r, 1 - src, b, mid);  // mid = r.begin + ⌊n/2⌋
}

}  // namespace bvhlab
