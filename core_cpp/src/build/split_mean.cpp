// Mean split (report §2.3.1): partition on whether a centroid lies below the mean centroid.
#include "bvhlab/split.h"

namespace bvhlab {

std::optional<Split> split_mean(SplitContext& ctx, Range r, int src, const NodeBounds& b, int axis) {
    double sum = 0.0;
    if (b.has_sum) {
        sum = b.centroid_sum[axis];  // gathered by the parent's bounds pass
    } else {
        const PrimRef* refs = ctx.buffers[src];
        for (std::uint32_t i = r.begin; i < r.end; ++i) sum += refs[i].centroid(axis);
    }
    return split_at_position(ctx, r, src, b, axis, static_cast<float>(sum / r.size()));
}

}  // namespace bvhlab
