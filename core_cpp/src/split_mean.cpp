// Mean split (report §2.3.1): partition on whether a centroid lies below the mean centroid.
#include "bvhlab/split.h"

namespace bvhlab {

std::optional<Split> split_mean(SplitContext& ctx, Range r, const NodeBounds& b, int axis) {
    double sum = 0.0;  // double: a float sum of a million centroids drifts visibly
    for (std::uint32_t i = r.begin; i < r.end; ++i) sum += ctx.refs[i].centroid(axis);
    float mean = static_cast<float>(sum / r.size());
    return split_at_position(ctx, r, b, axis, mean);
}

}  // namespace bvhlab
