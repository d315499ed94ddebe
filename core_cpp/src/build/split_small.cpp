// Exact SAH for small ranges (<= kSmallExact): every split position of the centroids sorted on
// each axis. Below a few buckets' worth of primitives this costs less than binning and never
// finds a worse split, so both SAH methods use it there. The three axes are sorted at once:
// vector lanes are axes, and each primitive's rank counts the primitives before it.
#include <limits>

#include "bvhlab/split.h"
#include "sah_sweep.h"

namespace bvhlab {
namespace {

static_assert(kSmallExact <= 255);

/// The references of a small range: boxes as (lo, -hi), twice the centroids, and their order
/// on each axis (a stable sort: ties keep input order).
struct SmallSet {
    std::uint32_t n;
    F4 lo[kSmallExact], neg_hi[kSmallExact], c2[kSmallExact];
    std::uint8_t order[3][kSmallExact];
    bool flat[3];

    SmallSet(const PrimRef* in, std::uint32_t count) : n(count) {
        const float inf = std::numeric_limits<float>::infinity();
        F4 cmin = F4::splat(inf), cmax = F4::splat(-inf);
        for (std::uint32_t i = 0; i < n; ++i) {
            lo[i] = in[i].lo4(), neg_hi[i] = neg(in[i].hi4()), c2[i] = in[i].lo4() + in[i].hi4();
            cmin = min(cmin, c2[i]), cmax = max(cmax, c2[i]);
        }
        for (int a = 0; a < 3; ++a) flat[a] = !(cmin.lane(a) < cmax.lane(a));
        rank_all();
    }
    /// rank of i = #{j : c2[j] < c2[i], or c2[j] == c2[i] and j < i}, per axis lane.
    void rank_all() {
        const F4 one = F4::splat(1.0f);
        for (std::uint32_t i = 0; i < n; ++i) {
            F4 rank = F4::splat(0.0f);
            for (std::uint32_t j = 0; j < i; ++j) rank = rank + (less_equal(c2[j], c2[i]) & one);
            for (std::uint32_t j = i + 1; j < n; ++j) rank = rank + (less(c2[j], c2[i]) & one);
            std::uint32_t r[4];
            truncate_to_u32(rank, r);
            for (int a = 0; a < 3; ++a) order[a][r[a]] = std::uint8_t(i);
        }
    }
    Cut cut(int a, const SahCost& sah, float inv_parent, Unions<kSmallExact + 3>& u) const {
        F4 slo[kSmallExact], sneg_hi[kSmallExact];
        for (std::uint32_t i = 0; i < n; ++i) slo[i] = lo[order[a][i]], sneg_hi[i] = neg_hi[order[a][i]];
        return cheapest_cut({slo, sneg_hi, 1, nullptr, n}, sah, inv_parent, u);
    }
    Aabb centroid_box(int a, std::uint32_t first, std::uint32_t last) const {
        const float inf = std::numeric_limits<float>::infinity();
        F4 cmin = F4::splat(inf), cmax = F4::splat(-inf);
        for (std::uint32_t i = first; i < last; ++i)
            cmin = min(cmin, c2[order[a][i]]), cmax = max(cmax, c2[order[a][i]]);
        return box_of(cmin * F4::splat(0.5f), cmax * F4::splat(0.5f));
    }
    static Aabb box_of(F4 lo, F4 hi) {
        return {{lo.lane(0), lo.lane(1), lo.lane(2)}, {hi.lane(0), hi.lane(1), hi.lane(2)}};
    }
};

}  // namespace

std::optional<Split> split_small_exact(SplitContext& ctx, Range r, int src, const NodeBounds& b, int axis) {
    const PrimRef* in = ctx.buffers[src] + r.begin;
    const SmallSet set(in, r.size());
    const float inv_parent = SahCost::inverse_area(b.box.half_area());
    const SahCost sah(ctx.config);
    Unions<kSmallExact + 3> unions, best_unions;
    Cut best;
    int best_axis = -1;
    for (int a = 0; a < 3; ++a) {
        if ((axis != kAllAxes && a != axis) || set.flat[a]) continue;
        const Cut cut = set.cut(a, sah, inv_parent, unions);
        if (cut.found && cut.cost < best.cost) best = cut, best_axis = a, best_unions = unions;
    }
    if (best_axis < 0) return std::nullopt;
    Split s;
    s.cost = best.cost;
    if (ctx.leaf_allowed && sah.leaf(set.n) <= best.cost) {
        s.leaf = true;
        return s;
    }
    const std::uint8_t* order = set.order[best_axis];
    PrimRef* out = ctx.buffers[1 - src] + r.begin;
    for (std::uint32_t i = 0; i < set.n; ++i) out[i] = in[order[i]];
    const std::uint32_t c = best.last_left, mid = c + 1;
    s.mid = r.begin + mid;
    s.left = {SmallSet::box_of(best_unions.left_lo[c], best_unions.left_hi[c]), set.centroid_box(best_axis, 0, mid)};
    s.right = {SmallSet::box_of(best_unions.right_lo[c], best_unions.right_hi[c]),
               set.centroid_box(best_axis, mid, set.n)};
    s.buffer = static_cast<std::uint8_t>(1 - src);
    return s;
}

}  // namespace bvhlab
