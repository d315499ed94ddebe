// Exact SAH for small ranges: every split position of the centroids sorted on an axis. Below a
// few dozen primitives this costs less than filling and sweeping B buckets, and never finds a
// worse split than binning, so both SAH methods use it there.
#include <algorithm>
#include <limits>

#include "bvhlab/split.h"

namespace bvhlab {
namespace {

NodeBounds bounds_in_order(const F4* lo, const F4* hi, const std::uint8_t* order, std::uint32_t first, std::uint32_t last) {
    const float inf = std::numeric_limits<float>::infinity();
    F4 blo = F4::splat(inf), bhi = F4::splat(-inf), clo = blo, chi = bhi;
    for (std::uint32_t i = first; i < last; ++i) {
        F4 a = lo[order[i]], b = hi[order[i]], c = (a + b) * F4::splat(0.5f);
        blo = min(blo, a), bhi = max(bhi, b), clo = min(clo, c), chi = max(chi, c);
    }
    auto vec = [](F4 v) { return Vec3{v.lane(0), v.lane(1), v.lane(2)}; };
    return {{vec(blo), vec(bhi)}, {vec(clo), vec(chi)}};
}

}  // namespace

std::optional<Split> split_small_exact(SplitContext& ctx, Range r, int src, const NodeBounds& b, int axis) {
    const std::uint32_t n = r.size();
    const PrimRef* in = ctx.buffers[src] + r.begin;
    const Vec3 extent = b.centroids.extent();
    const float parent_area = b.box.half_area();
    const float inv_parent = parent_area > 0 ? 1.0f / parent_area : 0.0f;
    const BuildConfig& cfg = ctx.config;
    const float inf = std::numeric_limits<float>::infinity();
    F4 lo[kSmallExact], hi[kSmallExact];
    for (std::uint32_t i = 0; i < n; ++i) lo[i] = in[i].lo4(), hi[i] = in[i].hi4();
    std::uint8_t order[kSmallExact], best_order[kSmallExact];
    float right_area[kSmallExact];
    float best_cost = inf;
    std::uint32_t best_mid = 0;

    for (int a = 0; a < 3; ++a) {
        if ((axis != kAllAxes && a != axis) || !(extent[a] > 0.0f)) continue;
        float key[kSmallExact];  // insertion sort by 2·centroid; stable, ties keep input order
        for (std::uint32_t i = 0; i < n; ++i) {
            float k = in[i].lo[a] + in[i].hi[a];
            std::uint32_t j = i;
            for (; j > 0 && key[j - 1] > k; --j) key[j] = key[j - 1], order[j] = order[j - 1];
            key[j] = k, order[j] = std::uint8_t(i);
        }
        F4 blo = F4::splat(inf), bhi = F4::splat(-inf);
        for (std::uint32_t i = n; i-- > 1;) {
            blo = min(blo, lo[order[i]]), bhi = max(bhi, hi[order[i]]);
            right_area[i] = half_area(blo, bhi);
        }
        blo = F4::splat(inf), bhi = F4::splat(-inf);
        for (std::uint32_t i = 1; i < n; ++i) {  // left = the first i in order
            blo = min(blo, lo[order[i - 1]]), bhi = max(bhi, hi[order[i - 1]]);
            float weighted = half_area(blo, bhi) * float(i) + right_area[i] * float(n - i);
            float ratio = parent_area > 0 ? weighted * inv_parent : float(n);
            float cost = cfg.traversal_cost + ratio * cfg.intersection_cost;
            if (cost < best_cost) best_cost = cost, best_mid = i, std::copy(order, order + n, best_order);
        }
    }
    if (best_mid == 0) return std::nullopt;
    PrimRef* out = ctx.buffers[1 - src] + r.begin;
    for (std::uint32_t i = 0; i < n; ++i) out[i] = in[best_order[i]];
    Split s;
    s.mid = r.begin + best_mid;
    s.left = bounds_in_order(lo, hi, best_order, 0, best_mid);
    s.right = bounds_in_order(lo, hi, best_order, best_mid, n);
    s.cost = best_cost;
    s.buffer = static_cast<std::uint8_t>(1 - src);
    return s;
}

}  // namespace bvhlab
