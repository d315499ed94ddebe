// Helpers shared by every split method: bounds, the SAH cost of a split, partitioning.
#include "bvhlab/split.h"

#ifdef BVHLAB_SSE
#include <emmintrin.h>
#endif

namespace bvhlab {

namespace {

/// Running bounds of a set of references; two of these alternate so that the min/max latency
/// chains of consecutive references overlap.
template <bool kSum>
struct BoundsAccumulator {
    F4 lo = F4::splat(std::numeric_limits<float>::infinity()), hi = F4::splat(-std::numeric_limits<float>::infinity());
    F4 clo = lo, chi = hi;
#ifdef BVHLAB_SSE
    __m128d sum_xy = _mm_setzero_pd(), sum_z = _mm_setzero_pd();  // in double: a million floats drift
#else
    double sum[3] = {0, 0, 0};
#endif
    void add(const PrimRef& p) {
        F4 a = p.lo4(), b = p.hi4(), c = a + b;  // twice the centroid; halved once in finish()
        lo = min(lo, a), hi = max(hi, b), clo = min(clo, c), chi = max(chi, c);
        if constexpr (!kSum) return;
#ifdef BVHLAB_SSE
        sum_xy = _mm_add_pd(sum_xy, _mm_cvtps_pd(c.v));
        sum_z = _mm_add_pd(sum_z, _mm_cvtps_pd(_mm_movehl_ps(c.v, c.v)));
#else
        for (int k = 0; k < 3; ++k) sum[k] += c.lane(k);
#endif
    }
    NodeBounds finish(const BoundsAccumulator& other) const {
        auto vec = [](F4 v) { return Vec3{v.lane(0), v.lane(1), v.lane(2)}; };
        const F4 half = F4::splat(0.5f);
        NodeBounds b{{vec(min(lo, other.lo)), vec(max(hi, other.hi))},
                     {vec(min(clo, other.clo) * half), vec(max(chi, other.chi) * half)}};
        if constexpr (!kSum) return b;
#ifdef BVHLAB_SSE
        double xy[2], z[2];
        _mm_storeu_pd(xy, _mm_add_pd(sum_xy, other.sum_xy)), _mm_storeu_pd(z, _mm_add_pd(sum_z, other.sum_z));
        b.centroid_sum[0] = 0.5 * xy[0], b.centroid_sum[1] = 0.5 * xy[1], b.centroid_sum[2] = 0.5 * z[0];
#else
        for (int k = 0; k < 3; ++k) b.centroid_sum[k] = 0.5 * (sum[k] + other.sum[k]);
#endif
        b.has_sum = true;
        return b;
    }
};

}  // namespace

template <bool kSum>
NodeBounds bounds(const PrimRef* refs, std::uint32_t n) {
    BoundsAccumulator<kSum> even, odd;
    std::uint32_t i = 0;
    for (; i + 1 < n; i += 2) even.add(refs[i]), odd.add(refs[i + 1]);
    if (i < n) even.add(refs[i]);
    return even.finish(odd);
}

NodeBounds bounds_of(const PrimRef* refs, std::uint32_t n, bool with_centroid_sum) {
    return with_centroid_sum ? bounds<true>(refs, n) : bounds<false>(refs, n);
}

Split split_at(SplitContext& ctx, Range r, int buf, const NodeBounds& parent, std::uint32_t mid) {
    const PrimRef* refs = ctx.buffers[buf];
    Split s;
    s.mid = mid;
    const bool sums = ctx.config.method == SplitMethod::Mean;  // only the mean split reads them
    s.left = bounds_of(refs + r.begin, mid - r.begin, sums);
    s.right = bounds_of(refs + mid, r.end - mid, sums);
    s.cost = split_cost(ctx.config, parent, s.left.box, mid - r.begin, s.right.box, r.end - mid);
    s.buffer = static_cast<std::uint8_t>(buf);
    return s;
}

std::optional<Split> split_at_position(SplitContext& ctx, Range r, int src, const NodeBounds& parent, int axis,
                                       float position) {
    // Compare 2·centroid with 2·position: the same order without a multiply per reference.
    const float twice = 2.0f * position;
    std::uint32_t mid = scatter_partition(ctx.buffers[src], ctx.buffers[1 - src], r,
                                          [=](const PrimRef& p) { return p.lo[axis] + p.hi[axis] < twice; });
    if (mid == r.begin || mid == r.end) return std::nullopt;
    return split_at(ctx, r, 1 - src, parent, mid);
}

Split split_even(SplitContext& ctx, Range r, int src, const NodeBounds& parent) {
    return split_at(ctx, r, src, parent, r.begin + r.size() / 2);
}

std::optional<Split> split_best_of_axes(SplitFunction split, SplitContext& ctx, Range r, int src,
                                        const NodeBounds& b) {
    std::optional<Split> best;
    int best_axis = -1, last_axis = -1;
    Vec3 extent = b.centroids.extent();
    for (int axis = 0; axis < 3; ++axis) {
        if (!(extent[axis] > 0.0f)) continue;
        std::optional<Split> s = split(ctx, r, src, b, axis);  // leaves src untouched
        last_axis = axis;
        if (s && (!best || s->cost < best->cost)) best = s, best_axis = axis;
    }
    if (best && best_axis != last_axis) best = split(ctx, r, src, b, best_axis);  // redo the winner's output
    return best;
}

}  // namespace bvhlab
