// Median split (report §2.3.1, PBRT "EqualCounts"): the first half gets the smaller centroids on
// the axis, in O(n) — never a sort. A histogram of the centroids finds the bucket that holds the
// median; one branch-free scatter puts everything below it left and above it right; then
// std::nth_element (the report's select_nth_unstable) orders just that bucket around the median.
#include <algorithm>
#include <cmath>

#include "bvhlab/split.h"
#include "partition.h"

namespace bvhlab {
namespace {

/// Ranges smaller than this are selected directly; a histogram would cost more than it saves.
constexpr std::uint32_t kDirectSelect = 128;

struct Bucketer {
    float origin, scale, top;
    int axis;
    std::uint32_t operator()(const PrimRef& p) const {
        return truncate_clamped(((p.lo[axis] + p.hi[axis]) - origin) * scale, top);  // on 2·centroid
    }
};

bool less_on(int axis, const PrimRef& p, const PrimRef& q) { return p.lo[axis] + p.hi[axis] < q.lo[axis] + q.hi[axis]; }

}  // namespace

std::optional<Split> split_median(SplitContext& ctx, Range r, int src, const NodeBounds& b, int axis) {
    const PrimRef* in = ctx.buffers[src];
    PrimRef* out = ctx.buffers[1 - src];
    const std::uint32_t mid = r.begin + r.size() / 2;
    auto less = [axis](const PrimRef& p, const PrimRef& q) { return less_on(axis, p, q); };
    if (r.size() < kDirectSelect) {
        std::copy(in + r.begin, in + r.end, out + r.begin);
        std::nth_element(out + r.begin, out + mid, out + r.end, less);
        return split_at(ctx, r, 1 - src, b, mid);
    }
    const std::uint32_t buckets = std::min<std::uint32_t>(1024, r.size() / 16);
    const float extent = b.centroids.extent()[axis];
    const float scale = extent > 0 ? float(buckets) / (2.0f * extent) : 0.0f;
    const Bucketer bucket{2.0f * b.centroids.lo[axis], std::isfinite(scale) ? scale : 0.0f, float(buckets - 1), axis};

    // 1. histogram, and the bucket holding the median
    auto& count = ctx.scratch.counts;
    count.assign(buckets, 0);
    for (std::uint32_t i = r.begin; i < r.end; ++i) ++count[bucket(in[i])];
    std::uint32_t median_bucket = 0, below = 0;
    while (below + count[median_bucket] <= mid - r.begin) below += count[median_bucket++];

    // 2. scatter: below | the median's bucket | above, each in input order; the bounds of what
    //    lies below and above are gathered on the way
    std::uint32_t cursor[3] = {r.begin, r.begin + below, r.begin + below + count[median_bucket]};
    const std::uint32_t bucket_begin = cursor[1], bucket_end = cursor[2];
    SideBounds sides[3];
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        const std::uint32_t k = bucket(in[i]);
        const std::uint32_t group = (k >= median_bucket) + (k > median_bucket);
        out[cursor[group]++] = in[i];
        sides[group].add<false>(in[i]);
    }
    // 3. select within the median's bucket, and add its two parts to the sides
    std::nth_element(out + bucket_begin, out + mid, out + bucket_end, less);
    for (std::uint32_t i = bucket_begin; i < bucket_end; ++i) sides[i < mid ? 0 : 2].add<false>(out[i]);
    return split_with(ctx, r, 1 - src, b, mid, sides[0].finish(false), sides[2].finish(false));
}

}  // namespace bvhlab
