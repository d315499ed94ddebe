// Mean split (report §2.3.1): partition on whether a centroid lies below the mean centroid.
#include "bvhlab/split.h"

namespace bvhlab {

std::optional<Split> split_mean(SplitContext& ctx, Range r, int src, const NodeBounds& b, int axis) {
    // The sum is gathered by the parent's bounds pass (the table of methods asks for it).
    const double sum = b.has_sum ? b.centroid_sum[axis] : bounds_of(ctx, r, src, true).centroid_sum[axis];
    return split_at_position(ctx, r, src, b, axis, static_cast<float>(sum / r.size()));
}

}  // namespace bvhlab
