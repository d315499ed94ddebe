// sbvh_splits.cpp — binning and the SAH sweep of both candidate splits (sbvh_splits.h).
#include "sbvh_splits.h"

#include <algorithm>
#include <limits>
#include <utility>
#include <vector>

#include "bvhlab/build_config.h"
#include "bvhlab/simd.h"
#include "chop.h"

namespace bvhlab::sbvh {
namespace {

/// A box in two vectors (lane 3 unused): binning grows thousands of them.
struct Box4 {
    F4 lo = F4::splat(std::numeric_limits<float>::infinity()), hi = F4::splat(-std::numeric_limits<float>::infinity());
    void grow(F4 l, F4 h) { lo = min(lo, l), hi = max(hi, h); }
    void grow(const Box4& b) { grow(b.lo, b.hi); }
    void grow(const Aabb& b) { grow(F4::set3(b.lo.x, b.lo.y, b.lo.z), F4::set3(b.hi.x, b.hi.y, b.hi.z)); }
    float half_area() const { return bvhlab::half_area(lo, hi); }  // Aabb::half_area's sums, in its order
    Aabb aabb() const {
        alignas(16) float l[4], h[4];
        lo.store(l), hi.store(h);
        return {{l[0], l[1], l[2]}, {h[0], h[1], h[2]}};
    }
};

struct Bin {
    Box4 box;
    std::uint32_t count = 0;  ///< object split: centroids in it; spatial split: references entering here
    std::uint32_t exits = 0;  ///< spatial split: references leaving here
};

/// The bins of x's three lanes among `bins` bins from `lo` at `scale` bins a unit: bin_of, lane by
/// lane, with the same IEEE operations.
void bins_of(F4 x, F4 lo, F4 scale, F4 top, std::uint32_t out[4]) {
    truncate_to_u32(min(max((x - lo) * scale, F4::splat(0.0f)), top), out);
}

/// The SAH sweep over one axis' bins: the cheapest boundary k (1..bins-1) between bins k-1 and k,
/// with the counts `left(b)` of bins entering the left side and `right(b)` the right. Only the right
/// sides' areas and counts are kept on the way back; the winner's right box is grown again at the
/// end (the same bins in the same order: the same box). `Sparse`: a bin whose count is 0 holds
/// nothing (the object split's), so the boundary after it costs what the one before it did and is
/// never cheaper: skipped, the same split found. Every node runs six sweeps, most of them over a
/// few references in mostly empty bins.
template <bool Sparse, class LeftCount, class RightCount>
void sweep(const Bin* bins, std::uint32_t count, float inv_area, const SahCost& sah, LeftCount left, RightCount right,
           float& best_cost, std::uint32_t& best_k, Aabb& best_left, Aabb& best_right, std::uint32_t& best_nl,
           std::uint32_t& best_nr) {
    float right_area[kMaxBins];
    std::uint32_t right_n[kMaxBins];
    Box4 box;
    std::uint32_t n = 0;
    float area = 0;
    for (std::uint32_t b = count; b-- > 1;) {
        if (!Sparse || bins[b].count) box.grow(bins[b].box), n += right(bins[b]), area = box.half_area();
        right_area[b] = area, right_n[b] = n;
    }
    box = Box4{}, n = 0;
    std::uint32_t found = 0, found_nl = 0;
    Box4 found_left;
    for (std::uint32_t k = 1; k < count; ++k) {
        if (Sparse && !bins[k - 1].count) continue;
        box.grow(bins[k - 1].box), n += left(bins[k - 1]);
        if (n == 0 || right_n[k] == 0) continue;
        const float cost = sah.split(inv_area, box.half_area(), n, right_area[k], right_n[k]);
        if (cost < best_cost) best_cost = cost, found = k, found_left = box, found_nl = n;
    }
    if (found == 0) return;
    Box4 right_box;
    for (std::uint32_t b = count; b-- > found;) right_box.grow(bins[b].box);
    best_k = found, best_left = found_left.aabb(), best_right = right_box.aabb();
    best_nl = found_nl, best_nr = right_n[found];
}

/// The boxes of the parts of triangle `v` (its nine coordinates; its reference's box `box_lo`, `box_hi`) in bins
/// first..last on `axis` (`lane`: that lane's mask; bin b between planes lo + width·b and
/// lo + width·(b+1), the first and last open outwards), grown into their bins: each part is the box
/// of the triangle's vertices in the slab and the edges' crossings of its two planes (the convex
/// polygon triangle ∩ slab), intersected with the reference's box. Each plane's crossings are
/// computed once, for the bins on both sides; the crossings are chop.h's edge_crossing in vectors.
void bin_triangle_parts(const float* v, F4 box_lo, F4 box_hi, int axis, F4 lane, std::uint32_t first,
                        std::uint32_t last, float lo, float width, Bin* bins) {
    float c[3] = {v[axis], v[3 + axis], v[6 + axis]};
    int order[3] = {0, 1, 2};  // the vertices in order along the axis
    if (c[1] < c[0]) std::swap(c[0], c[1]), std::swap(order[0], order[1]);
    if (c[2] < c[1]) std::swap(c[1], c[2]), std::swap(order[1], order[2]);
    if (c[1] < c[0]) std::swap(c[0], c[1]), std::swap(order[0], order[1]);
    F4 p[3];
    for (int k = 0; k < 3; ++k) {
        const float* q = v + 3 * order[k];
        p[k] = F4::set3(q[0], q[1], q[2]);
    }
    const F4 widen = F4::splat(0x1p-20f);
    auto cross = [&](int i, int j, float pos, Box4& out) {  // edge_crossing(p[i], p[j], axis, pos)
        const float t = (pos - c[i]) / (c[j] - c[i]);
        const F4 at = p[i] + (p[j] - p[i]) * F4::splat(t);
        const F4 err = (max(p[i], neg(p[i])) + max(p[j], neg(p[j]))) * widen;
        const F4 plane = F4::splat(pos);
        out.grow(select(lane, plane, at - err), select(lane, plane, at + err));
    };
    auto crossings = [&](float pos) {  // the polygon's points on the plane
        Box4 out;
        if (c[0] < pos && pos < c[2]) cross(0, 2, pos, out);
        if (c[0] < pos && pos < c[1]) cross(0, 1, pos, out);
        if (c[1] < pos && pos < c[2]) cross(1, 2, pos, out);
        return out;
    };
    const float inf = std::numeric_limits<float>::infinity();
    float below = -inf;
    Box4 at_below;  // crossings of the plane below the bin
    for (std::uint32_t b = first; b <= last; ++b) {
        const float above = b == last ? inf : lo + width * float(b + 1);
        const Box4 at_above = b == last ? Box4{} : crossings(above);
        Box4 part = at_below;
        part.grow(at_above);
        for (int k = 0; k < 3; ++k)
            if (below <= c[k] && c[k] <= above) part.grow(p[k], p[k]);
        const F4 part_lo = max(select(lane, max(part.lo, F4::splat(below)), part.lo), box_lo);
        const F4 part_hi = min(select(lane, min(part.hi, F4::splat(above)), part.hi), box_hi);
        if (!any_lane(less(part_hi, part_lo))) bins[b].box.grow(part_lo, part_hi);
        below = above, at_below = at_above;
    }
}

}  // namespace

ObjectSplit find_object_split(const PrimRef* refs, std::uint32_t n, const Aabb& span, float area,
                              const BinSetup& setup) {
    const std::uint32_t count = setup.bins;
    thread_local std::vector<Bin> storage;
    storage.assign(3 * std::size_t(count), Bin{});
    Bin* bins[3] = {storage.data(), storage.data() + count, storage.data() + 2 * count};
    float scale[3];
    const Vec3 extent = span.extent();
    for (int a = 0; a < 3; ++a) scale[a] = extent[a] > 0 ? float(count) / extent[a] : 0.0f;  // as object_goes_left
    const F4 lo4 = F4::set3(span.lo.x, span.lo.y, span.lo.z), scale4 = F4::set3(scale[0], scale[1], scale[2]);
    const F4 top = F4::splat(float(count - 1)), half = F4::splat(0.5f);
    for (std::uint32_t i = 0; i < n; ++i) {
        const F4 lo = refs[i].lo4(), hi = refs[i].hi4();
        std::uint32_t k[4];
        bins_of((lo + hi) * half, lo4, scale4, top, k);  // PrimRef::centroid's 0.5 · (lo + hi)
        for (int a = 0; a < 3; ++a) bins[a][k[a]].box.grow(lo, hi), ++bins[a][k[a]].count;
    }
    ObjectSplit best;
    const float inv_area = SahCost::inverse_area(area);
    for (int a = 0; a < 3; ++a) {
        if (scale[a] == 0.0f) continue;
        std::uint32_t k = 0, nl = 0, nr = 0;
        const float before = best.cost;
        auto counted = [](const Bin& b) { return b.count; };
        sweep<true>(bins[a], count, inv_area, setup.sah, counted, counted, best.cost, k, best.left, best.right, nl, nr);
        if (best.cost < before) best.axis = a, best.bin = k;
    }
    return best;
}

SpatialSplit find_spatial_split(const GeometryView& g, const PrimRef* refs, std::uint32_t n, const Aabb& box,
                                const BinSetup& setup) {
    const std::uint32_t count = setup.spatial_bins;
    thread_local std::vector<Bin> storage;
    storage.assign(3 * std::size_t(count), Bin{});
    Bin* bins[3] = {storage.data(), storage.data() + count, storage.data() + 2 * count};
    float scale[3], width[3];
    for (int a = 0; a < 3; ++a) {
        const float extent = box.hi[a] - box.lo[a];
        scale[a] = extent > 0 ? float(count) / extent : 0.0f;
        width[a] = extent / float(count);
    }
    const F4 lo4 = F4::set3(box.lo.x, box.lo.y, box.lo.z), scale4 = F4::set3(scale[0], scale[1], scale[2]);
    const F4 top = F4::splat(float(count - 1));
    static constexpr float kOnes[3][4] = {{0, 1, 1, 1}, {1, 0, 1, 1}, {1, 1, 0, 1}};  // 0 in the axis' lane
    const F4 lanes[3] = {less(F4::load(kOnes[0]), F4::splat(0.5f)), less(F4::load(kOnes[1]), F4::splat(0.5f)),
                         less(F4::load(kOnes[2]), F4::splat(0.5f))};  // each axis' lane mask
    for (std::uint32_t i = 0; i < n; ++i) {
        const PrimRef& r = refs[i];
        const F4 lo = r.lo4(), hi = r.hi4();
        std::uint32_t first[4], last[4];
        bins_of(lo, lo4, scale4, top, first), bins_of(hi, lo4, scale4, top, last);
        bool spans = false;
        for (int a = 0; a < 3; ++a) {
            ++bins[a][first[a]].count, ++bins[a][last[a]].exits;
            if (first[a] == last[a]) bins[a][first[a]].box.grow(lo, hi);
            spans |= first[a] != last[a];
        }
        if (!spans) continue;
        // the reference is chopped at each bin boundary it spans, its parts binned one by one
        const bool sphere = is_sphere_ref(r.ref);
        const float* v = sphere ? nullptr : g.triangles + 9 * std::size_t(ref_index(r.ref));
        for (int a = 0; a < 3; ++a) {
            if (first[a] == last[a]) continue;
            if (!sphere) {
                bin_triangle_parts(v, lo, hi, a, lanes[a], first[a], last[a], box.lo[a], width[a], bins[a]);
                continue;
            }
            Aabb rest = r.box();
            for (std::uint32_t b = first[a]; b < last[a] && !rest.empty(); ++b) {
                Aabb below, above;
                chop_box(rest, a, box.lo[a] + width[a] * float(b + 1), below, above);
                if (!below.empty()) bins[a][b].box.grow(below);
                rest = above;
            }
            if (!rest.empty()) bins[a][last[a]].box.grow(rest);
        }
    }
    SpatialSplit best;
    const float inv_area = SahCost::inverse_area(box.half_area());
    for (int a = 0; a < 3; ++a) {
        if (scale[a] == 0.0f) continue;
        std::uint32_t k = 0, nl = 0, nr = 0;
        const float before = best.cost;
        sweep<false>(
            bins[a], count, inv_area, setup.sah, [](const Bin& b) { return b.count; },
            [](const Bin& b) { return b.exits; }, best.cost, k, best.left, best.right, nl, nr);
        if (best.cost < before) {
            best.axis = a, best.position = box.lo[a] + width[a] * float(k);
            best.left_count = nl, best.right_count = nr;
        }
    }
    return best;
}

}  // namespace bvhlab::sbvh
