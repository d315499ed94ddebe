// Helpers shared by every split method: bounds, the SAH cost of a split, partitioning.
#include <algorithm>

#include "bvhlab/split.h"

namespace bvhlab {

NodeBounds bounds_of(const PrimRef* refs, std::uint32_t n) {
    const float inf = std::numeric_limits<float>::infinity();
    F4 lo = F4::splat(inf), hi = F4::splat(-inf), clo = lo, chi = hi;
    const F4 half = F4::splat(0.5f);
    for (std::uint32_t i = 0; i < n; ++i) {
        F4 a = refs[i].lo4(), b = refs[i].hi4(), c = (a + b) * half;
        lo = min(lo, a);
        hi = max(hi, b);
        clo = min(clo, c);
        chi = max(chi, c);
    }
    auto vec = [](F4 v) { return Vec3{v.lane(0), v.lane(1), v.lane(2)}; };
    return {{vec(lo), vec(hi)}, {vec(clo), vec(chi)}};
}

float split_cost(const BuildConfig& config, const NodeBounds& parent, const Aabb& left,
                 std::uint32_t n_left, const Aabb& right, std::uint32_t n_right) {
    float parent_area = parent.box.half_area();
    float weighted = left.half_area() * float(n_left) + right.half_area() * float(n_right);
    // A box with no area (all primitives on a line or a point) gives no probabilities; count
    // every primitive as hit then, so splitting never looks cheaper than it is.
    float ratio = parent_area > 0.0f ? weighted / parent_area : float(n_left + n_right);
    return config.traversal_cost + ratio * config.intersection_cost;
}

Split split_at(SplitContext& ctx, Range r, const NodeBounds& parent, std::uint32_t mid) {
    Split s;
    s.mid = mid;
    s.left = bounds_of(ctx.refs + r.begin, mid - r.begin);
    s.right = bounds_of(ctx.refs + mid, r.end - mid);
    s.cost = split_cost(ctx.config, parent, s.left.box, mid - r.begin, s.right.box, r.end - mid);
    return s;
}

std::optional<Split> split_at_position(SplitContext& ctx, Range r, const NodeBounds& parent, int axis,
                                       float position) {
    PrimRef* first = ctx.refs + r.begin;
    PrimRef* last = ctx.refs + r.end;
    PrimRef* mid = std::partition(first, last, [=](const PrimRef& p) { return p.centroid(axis) < position; });
    if (mid == first || mid == last) return std::nullopt;
    return split_at(ctx, r, parent, static_cast<std::uint32_t>(mid - ctx.refs));
}

Split split_even(SplitContext& ctx, Range r, const NodeBounds& parent) {
    return split_at(ctx, r, parent, r.begin + r.size() / 2);
}

std::optional<Split> split_best_of_axes(SplitFunction split, SplitContext& ctx, Range r, const NodeBounds& b) {
    PrimRef* first = ctx.refs + r.begin;
    auto& original = ctx.scratch.original;
    auto& best_refs = ctx.scratch.best;
    original.assign(first, first + r.size());
    std::optional<Split> best;
    bool range_holds_best = false;
    Vec3 extent = b.centroids.extent();
    for (int axis = 0; axis < 3; ++axis) {
        if (!(extent[axis] > 0.0f)) continue;
        std::copy(original.begin(), original.end(), first);
        std::optional<Split> s = split(ctx, r, b, axis);
        range_holds_best = s && (!best || s->cost < best->cost);
        if (range_holds_best) {
            best = s;
            best_refs.assign(first, first + r.size());
        }
    }
    if (!best) std::copy(original.begin(), original.end(), first);
    else if (!range_holds_best) std::copy(best_refs.begin(), best_refs.end(), first);
    return best;
}

}  // namespace bvhlab
