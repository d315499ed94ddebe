// sbvh_splits.cpp — binning and the SAH sweep of both candidate splits (sbvh_splits.h).
#include "sbvh_splits.h"

#include <vector>

#include "bvhlab/build_config.h"
#include "chop.h"

namespace bvhlab::sbvh {
namespace {

struct Bin {
    Aabb box;
    std::uint32_t count = 0;  ///< object split: centroids in it; spatial split: references entering here
    std::uint32_t exits = 0;  ///< spatial split: references leaving here
};

/// The SAH sweep over one axis' bins: the cheapest boundary k (1..bins-1) between bins k-1 and k,
/// with the counts `left(b)` of bins entering the left side and `right(b)` the right.
template <class LeftCount, class RightCount>
void sweep(const Bin* bins, std::uint32_t count, float inv_area, const SahCost& sah, LeftCount left, RightCount right,
           float& best_cost, std::uint32_t& best_k, Aabb& best_left, Aabb& best_right, std::uint32_t& best_nl,
           std::uint32_t& best_nr) {
    thread_local std::vector<Aabb> right_box;
    thread_local std::vector<std::uint32_t> right_n;
    right_box.resize(count), right_n.resize(count);
    Aabb box;
    std::uint32_t n = 0;
    for (std::uint32_t b = count; b-- > 1;) {
        box.grow(bins[b].box), n += right(bins[b]);
        right_box[b] = box, right_n[b] = n;
    }
    box = Aabb{}, n = 0;
    for (std::uint32_t k = 1; k < count; ++k) {
        box.grow(bins[k - 1].box), n += left(bins[k - 1]);
        if (n == 0 || right_n[k] == 0) continue;
        const float cost = sah.split(inv_area, box.half_area(), n, right_box[k].half_area(), right_n[k]);
        if (cost < best_cost) {
            best_cost = cost, best_k = k, best_left = box, best_right = right_box[k];
            best_nl = n, best_nr = right_n[k];
        }
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
    for (std::uint32_t i = 0; i < n; ++i) {
        const PrimRef& r = refs[i];
        const Aabb box = r.box();
        for (int a = 0; a < 3; ++a) {
            Bin& bin = bins[a][bin_of(r.centroid(a), span.lo[a], scale[a], count)];
            bin.box.grow(box), ++bin.count;
        }
    }
    ObjectSplit best;
    const float inv_area = SahCost::inverse_area(area);
    for (int a = 0; a < 3; ++a) {
        if (scale[a] == 0.0f) continue;
        std::uint32_t k = 0, nl = 0, nr = 0;
        const float before = best.cost;
        auto counted = [](const Bin& b) { return b.count; };
        sweep(bins[a], count, inv_area, setup.sah, counted, counted, best.cost, k, best.left, best.right, nl, nr);
        if (best.cost < before) best.axis = a, best.bin = k;
    }
    return best;
}

SpatialSplit find_spatial_split(const GeometryView& g, const PrimRef* refs, std::uint32_t n, const Aabb& box,
                                const BinSetup& setup) {
    const std::uint32_t count = setup.bins;
    thread_local std::vector<Bin> storage;
    storage.assign(3 * std::size_t(count), Bin{});
    Bin* bins[3] = {storage.data(), storage.data() + count, storage.data() + 2 * count};
    float scale[3], width[3];
    for (int a = 0; a < 3; ++a) {
        const float extent = box.hi[a] - box.lo[a];
        scale[a] = extent > 0 ? float(count) / extent : 0.0f;
        width[a] = extent / float(count);
    }
    for (std::uint32_t i = 0; i < n; ++i) {
        const PrimRef& r = refs[i];
        std::uint32_t first[3], last[3];
        bool spans = false;
        for (int a = 0; a < 3; ++a) {
            first[a] = bin_of(r.lo[a], box.lo[a], scale[a], count),
            last[a] = bin_of(r.hi[a], box.lo[a], scale[a], count);
            ++bins[a][first[a]].count, ++bins[a][last[a]].exits;
            if (first[a] == last[a]) bins[a][first[a]].box.grow(r.box());
            spans |= first[a] != last[a];
        }
        if (!spans) continue;
        // the reference is chopped at each bin boundary it spans, its parts binned one by one
        const bool sphere = is_sphere_ref(r.ref);
        Vec3 v[3];
        if (!sphere) {
            const std::size_t t = ref_index(r.ref);
            v[0] = g.vertex(t, 0), v[1] = g.vertex(t, 1), v[2] = g.vertex(t, 2);
        }
        for (int a = 0; a < 3; ++a) {
            if (first[a] == last[a]) continue;
            Aabb rest = r.box();
            for (std::uint32_t b = first[a]; b < last[a] && !rest.empty(); ++b) {
                Aabb below, above;
                const float pos = box.lo[a] + width[a] * float(b + 1);
                if (sphere) {
                    chop_box(rest, a, pos, below, above);
                } else {
                    chop_triangle(v, rest, a, pos, below, above);
                }
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
        sweep(
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
