// Binned SAH (report §2.3.2, PBRT §4.3.2): drop centroids into B equal buckets along the axis,
// then find the cheapest bucket boundary with one sweep from the right and one from the left —
// O(n + B), the improvement over the O(n + B²) loop the report says its implementation had.
#include <algorithm>
#include <cmath>

#include "bvhlab/split.h"

namespace bvhlab {
namespace {

/// One bucket: the box of its primitives and of their centroids (64 bytes, one cache line).
struct alignas(64) Bin {
    F4 lo, hi, clo, chi;
};

/// B buckets on one axis. Consecutive references alternate between two copies so that runs of
/// references in the same bucket do not wait on each other's stores; the copies merge after.
struct Bins {
    Bin bin[2][kMaxBins];
    std::uint32_t count[2][kMaxBins];

    void reset(std::uint32_t n) {
        const F4 inf = F4::splat(std::numeric_limits<float>::infinity()), ninf = F4::splat(-std::numeric_limits<float>::infinity());
        for (auto& set : bin)
            for (std::uint32_t k = 0; k < n; ++k) set[k] = {inf, ninf, inf, ninf};
        for (auto& set : count) std::fill(set, set + n, 0u);
    }
    void add(int copy, std::uint32_t k, F4 lo, F4 hi, F4 c) {
        Bin& b = bin[copy][k];
        b.lo = min(b.lo, lo), b.hi = max(b.hi, hi), b.clo = min(b.clo, c), b.chi = max(b.chi, c);
        ++count[copy][k];
    }
    void merge_copies(std::uint32_t n) {
        for (std::uint32_t k = 0; k < n; ++k) {
            Bin& a = bin[0][k];
            const Bin& b = bin[1][k];
            a.lo = min(a.lo, b.lo), a.hi = max(a.hi, b.hi), a.clo = min(a.clo, b.clo), a.chi = max(a.chi, b.chi);
            count[0][k] += count[1][k];
        }
    }
};

/// Union of buckets [first, last) as NodeBounds.
NodeBounds merge(const Bins& bins, std::uint32_t first, std::uint32_t last) {
    const float inf = std::numeric_limits<float>::infinity();
    F4 lo = F4::splat(inf), hi = F4::splat(-inf), clo = lo, chi = hi;
    for (std::uint32_t k = first; k < last; ++k) {
        const Bin& b = bins.bin[0][k];
        lo = min(lo, b.lo), hi = max(hi, b.hi), clo = min(clo, b.clo), chi = max(chi, b.chi);
    }
    auto vec = [](F4 v) { return Vec3{v.lane(0), v.lane(1), v.lane(2)}; };
    return {{vec(lo), vec(hi)}, {vec(clo), vec(chi)}};
}

struct Candidate {
    float cost = std::numeric_limits<float>::infinity();
    int axis = -1;
    std::uint32_t last_left_bin = 0;  ///< buckets [0, last_left_bin] go left
};

/// The O(B) sweep: cheapest boundary of one axis's buckets.
void sweep(const Bins& bins, std::uint32_t n_bins, int axis, const BuildConfig& config, float parent_area,
           Candidate& best) {
    const float inf = std::numeric_limits<float>::infinity();
    float right_area[kMaxBins];
    std::uint32_t right_count[kMaxBins];
    F4 lo = F4::splat(inf), hi = F4::splat(-inf);
    std::uint32_t n = 0;
    for (std::uint32_t k = n_bins - 1; k > 0; --k) {
        lo = min(lo, bins.bin[0][k].lo), hi = max(hi, bins.bin[0][k].hi), n += bins.count[0][k];
        right_area[k] = half_area(lo, hi), right_count[k] = n;
    }
    lo = F4::splat(inf), hi = F4::splat(-inf), n = 0;
    const float inv_parent = parent_area > 0 ? 1.0f / parent_area : 0.0f;
    for (std::uint32_t k = 0; k + 1 < n_bins; ++k) {
        lo = min(lo, bins.bin[0][k].lo), hi = max(hi, bins.bin[0][k].hi), n += bins.count[0][k];
        if (n == 0 || right_count[k + 1] == 0) continue;
        float weighted = half_area(lo, hi) * float(n) + right_area[k + 1] * float(right_count[k + 1]);
        float ratio = parent_area > 0 ? weighted * inv_parent : float(n + right_count[k + 1]);
        float cost = config.traversal_cost + ratio * config.intersection_cost;
        if (cost < best.cost) best = {cost, axis, k};
    }
}

/// Bucket of a reference on one axis, from 2·centroid (one add, no multiply by ½). Binning and
/// partitioning call this same function, so both see the same bucket.
struct Bucketer {
    float origin = 0, scale = 0, top = 0;
    Bucketer() = default;
    Bucketer(const Aabb& centroids, int axis, std::uint32_t n_bins) {
        float extent = centroids.hi[axis] - centroids.lo[axis];
        float s = float(n_bins) / (2.0f * extent);
        origin = 2.0f * centroids.lo[axis];
        scale = extent > 0 && std::isfinite(s) ? s : 0.0f;
        top = float(n_bins - 1);
    }
    std::uint32_t operator()(const PrimRef& p, int axis) const {
        float k = (p.lo[axis] + p.hi[axis] - origin) * scale;
        return static_cast<std::uint32_t>(std::min(std::max(k, 0.0f), top));
    }
};

/// Bins every reference on the axes [first, last] (those with an extent) and stores its bucket
/// on each axis in `code` (one byte per axis), so the partition reads rather than recomputes it.
template <bool kOneAxis>
void bin_range(PrimRef* refs, Range r, int first, int last, const Vec3& extent, Bins* bins, const Bucketer* bucket) {
    const F4 half = F4::splat(0.5f);
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        PrimRef& p = refs[i];
        F4 lo = p.lo4(), hi = p.hi4(), c = (lo + hi) * half;
        if constexpr (kOneAxis) {
            std::uint32_t k = bucket[first](p, first);
            p.code = k << (8 * first);
            bins[first].add(int(i & 1), k, lo, hi, c);
        } else {
            std::uint32_t code = 0;
            for (int a = first; a <= last; ++a) {
                if (!(extent[a] > 0.0f)) continue;
                std::uint32_t k = bucket[a](p, a);
                code |= k << (8 * a);
                bins[a].add(int(i & 1), k, lo, hi, c);
            }
            p.code = code;
        }
    }
}

}  // namespace

std::optional<Split> split_binned_sah(SplitContext& ctx, Range r, int src, const NodeBounds& b, int axis) {
    if (r.size() <= kSmallExact) return split_small_exact(ctx, r, src, b, axis);
    const std::uint32_t n_bins = ctx.config.bins;
    const int first_axis = axis == kAllAxes ? 0 : axis, last_axis = axis == kAllAxes ? 2 : axis;
    const Vec3 extent = b.centroids.extent();
    PrimRef* in = ctx.buffers[src];
    Bins bins[3];
    Bucketer bucket[3];

    // Binning: one pass over the references, per axis asked for.
    for (int a = first_axis; a <= last_axis; ++a) {
        if (!(extent[a] > 0.0f)) continue;
        bins[a].reset(n_bins);
        bucket[a] = Bucketer(b.centroids, a, n_bins);
    }
    if (first_axis == last_axis) bin_range<true>(in, r, first_axis, last_axis, extent, bins, bucket);
    else bin_range<false>(in, r, first_axis, last_axis, extent, bins, bucket);

    // Sweep every binned axis; keep the cheapest boundary.
    Candidate best;
    const float parent_area = b.box.half_area();
    for (int a = first_axis; a <= last_axis; ++a) {
        if (!(extent[a] > 0.0f)) continue;
        bins[a].merge_copies(n_bins);
        sweep(bins[a], n_bins, a, ctx.config, parent_area, best);
    }
    if (best.axis < 0) return std::nullopt;

    // Scatter into the other buffer by bucket; the child bounds are the unions of their buckets.
    const int a = best.axis;
    const std::uint32_t last_left = best.last_left_bin;
    const int shift = 8 * a;
    Split s;
    s.mid = scatter_partition(in, ctx.buffers[1 - src], r,
                              [=](const PrimRef& p) { return ((p.code >> shift) & 0xffu) <= last_left; });
    s.left = merge(bins[a], 0, last_left + 1);
    s.right = merge(bins[a], last_left + 1, n_bins);
    s.cost = best.cost;
    s.buffer = static_cast<std::uint8_t>(1 - src);
    return s;
}

}  // namespace bvhlab
