// Binned SAH (report §2.3.2, PBRT §4.3.2): drop centroids into B equal buckets along the axis,
// then find the cheapest bucket boundary with one sweep from the right and one from the left —
// O(n + B), the improvement over the O(n + B²) loop the report says its implementation had.
#include <algorithm>
#include <cmath>

#include "bvhlab/split.h"

namespace bvhlab {
namespace {

/// B buckets on one axis: the box of the primitives and of their centroids, and a count.
struct Bins {
    F4 lo[kMaxBins], hi[kMaxBins], clo[kMaxBins], chi[kMaxBins];
    std::uint32_t count[kMaxBins];

    void reset(std::uint32_t n) {
        const F4 inf = F4::splat(std::numeric_limits<float>::infinity()), ninf = F4::splat(-std::numeric_limits<float>::infinity());
        for (std::uint32_t k = 0; k < n; ++k) lo[k] = clo[k] = inf, hi[k] = chi[k] = ninf, count[k] = 0;
    }
    void add(std::uint32_t k, F4 plo, F4 phi, F4 c) {
        lo[k] = min(lo[k], plo), hi[k] = max(hi[k], phi);
        clo[k] = min(clo[k], c), chi[k] = max(chi[k], c);
        ++count[k];
    }
};

float half_area(F4 lo, F4 hi) {
    float e[4];
    (hi - lo).store(e);
    return e[0] > 0 || e[1] > 0 || e[2] > 0 ? e[0] * e[1] + e[1] * e[2] + e[2] * e[0] : 0.0f;
}

/// Union of buckets [first, last) as NodeBounds.
NodeBounds merge(const Bins& bins, std::uint32_t first, std::uint32_t last) {
    const float inf = std::numeric_limits<float>::infinity();
    F4 lo = F4::splat(inf), hi = F4::splat(-inf), clo = lo, chi = hi;
    for (std::uint32_t k = first; k < last; ++k)
        lo = min(lo, bins.lo[k]), hi = max(hi, bins.hi[k]), clo = min(clo, bins.clo[k]), chi = max(chi, bins.chi[k]);
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
        lo = min(lo, bins.lo[k]), hi = max(hi, bins.hi[k]), n += bins.count[k];
        right_area[k] = half_area(lo, hi), right_count[k] = n;
    }
    lo = F4::splat(inf), hi = F4::splat(-inf), n = 0;
    const float inv_parent = parent_area > 0 ? 1.0f / parent_area : 0.0f;
    for (std::uint32_t k = 0; k + 1 < n_bins; ++k) {
        lo = min(lo, bins.lo[k]), hi = max(hi, bins.hi[k]), n += bins.count[k];
        if (n == 0 || right_count[k + 1] == 0) continue;
        float weighted = half_area(lo, hi) * float(n) + right_area[k + 1] * float(right_count[k + 1]);
        float ratio = parent_area > 0 ? weighted * inv_parent : float(n + right_count[k + 1]);
        float cost = config.traversal_cost + ratio * config.intersection_cost;
        if (cost < best.cost) best = {cost, axis, k};
    }
}

/// Bucket index of each centroid on all three axes, 4-wide; lanes with no extent get bucket 0.
struct Binner {
    F4 origin, scale, top;
    Binner(const Aabb& centroids, std::uint32_t n_bins) {
        Vec3 e = centroids.extent();
        float s[4] = {0, 0, 0, 0}, o[4] = {centroids.lo.x, centroids.lo.y, centroids.lo.z, 0};
        for (int a = 0; a < 3; ++a) {
            float inv = float(n_bins) / e[a];
            s[a] = e[a] > 0 && std::isfinite(inv) ? inv : 0.0f;
        }
        origin = F4::load(o), scale = F4::load(s), top = F4::splat(float(n_bins - 1));
    }
    /// Bucket indices packed one byte per axis (bits 0-7 x, 8-15 y, 16-23 z).
    std::uint32_t operator()(F4 c) const {
        F4 k = min(max((c - origin) * scale, F4::splat(0.0f)), top);
        float f[4];
        k.store(f);
        return std::uint32_t(f[0]) | std::uint32_t(f[1]) << 8 | std::uint32_t(f[2]) << 16;
    }
};

inline std::uint32_t bucket(std::uint32_t packed, int axis) { return (packed >> (8 * axis)) & 0xffu; }

}  // namespace

std::optional<Split> split_binned_sah(SplitContext& ctx, Range r, const NodeBounds& b, int axis) {
    const std::uint32_t n_bins = ctx.config.bins;
    const int first_axis = axis == kAllAxes ? 0 : axis, last_axis = axis == kAllAxes ? 2 : axis;
    Bins bins[3];
    for (int a = first_axis; a <= last_axis; ++a) bins[a].reset(n_bins);

    // Binning: one pass; each reference remembers its buckets (in `code`) so the partition below
    // uses exactly the bucket the sweep counted it in.
    const Binner binner(b.centroids, n_bins);
    const F4 half = F4::splat(0.5f);
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        PrimRef& p = ctx.refs[i];
        F4 lo = p.lo4(), hi = p.hi4(), c = (lo + hi) * half;
        p.code = binner(c);
        for (int a = first_axis; a <= last_axis; ++a) bins[a].add(bucket(p.code, a), lo, hi, c);
    }

    // Sweep every binned axis that has an extent; keep the cheapest boundary.
    Candidate best;
    const float parent_area = b.box.half_area();
    Vec3 extent = b.centroids.extent();
    for (int a = first_axis; a <= last_axis; ++a)
        if (extent[a] > 0.0f) sweep(bins[a], n_bins, a, ctx.config, parent_area, best);
    if (best.axis < 0) return std::nullopt;

    // Partition on the stored buckets; the child bounds are the unions of their buckets.
    const int a = best.axis;
    const std::uint32_t last_left = best.last_left_bin;
    PrimRef* mid = std::partition(ctx.refs + r.begin, ctx.refs + r.end,
                                  [=](const PrimRef& p) { return bucket(p.code, a) <= last_left; });
    Split s;
    s.mid = static_cast<std::uint32_t>(mid - ctx.refs);
    s.left = merge(bins[a], 0, last_left + 1);
    s.right = merge(bins[a], last_left + 1, n_bins);
    s.cost = best.cost;
    return s;
}

}  // namespace bvhlab
