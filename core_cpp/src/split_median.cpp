// Median split (report §2.3.1, PBRT "EqualCounts"): reorder so the first half has the smaller
// centroids on the axis, in O(n) with std::nth_element instead of a full sort.
#include <algorithm>

#include "bvhlab/split.h"

namespace bvhlab {

std::optional<Split> split_median(SplitContext& ctx, Range r, const NodeBounds& b, int axis) {
    std::uint32_t mid = r.begin + r.size() / 2;
    std::nth_element(ctx.refs + r.begin, ctx.refs + mid, ctx.refs + r.end,
                     [axis](const PrimRef& p, const PrimRef& q) { return p.centroid(axis) < q.centroid(axis); });
    return split_at(ctx, r, b, mid);
}

}  // namespace bvhlab
