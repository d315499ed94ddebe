// Midpoint split (PBRT "Middle"): partition at the middle of the centroid bounds on the axis.
#include "bvhlab/split.h"

namespace bvhlab {

std::optional<Split> split_midpoint(SplitContext& ctx, Range r, int src, const NodeBounds& b, int axis) {
    float middle = 0.5f * (b.centroids.lo[axis] + b.centroids.hi[axis]);
    return split_at_position(ctx, r, src, b, axis, middle);
}

}  // namespace bvhlab
