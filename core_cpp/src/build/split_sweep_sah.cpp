// Full-sweep SAH: sort the centroids on the axis and evaluate the SAH at every one of the n - 1
// split positions, with one suffix sweep and one prefix sweep (the exact version of §2.3.2 that
// the report describes before turning to binning). O(n log n) per node: the quality reference.
#include <algorithm>
#include <limits>

#include "bvhlab/split.h"
#include "sort_chunks.h"

namespace bvhlab {
namespace {

struct Best {
    float cost = std::numeric_limits<float>::infinity();
    int axis = -1;
    std::uint32_t mid = 0;  ///< offset within the range
};

/// ctx.scratch.sorted becomes r's references of `in` sorted on `axis`: on the pool in chunks where
/// the build has several threads and the node is at the top of the tree (chunk_count;
/// sort_in_chunks), else by one std::sort (on one thread the chunks' merges only cost: 1M
/// references 0.092 → 0.107 s, the review's).
void sort_on_axis(SplitContext& ctx, Range r, const PrimRef* in, int axis) {
    auto& sorted = ctx.scratch.sorted;
    sorted.assign(in + r.begin, in + r.end);
    const std::uint32_t chunks = ctx.parallel && ctx.parallel->threads > 1 ? chunk_count(ctx, r) : 1;
    // Ties keep a fixed order (by reference): a total order, so the result depends on nothing but
    // the input (not on the chunks)
    sort_in_chunks(ctx, chunks, sorted, ctx.scratch.merged, [axis](const PrimRef& p, const PrimRef& q) {
        float cp = p.lo[axis] + p.hi[axis], cq = q.lo[axis] + q.hi[axis];
        return cp < cq || (cp == cq && p.ref < q.ref);
    });
}

/// Sweeps one sorted axis and records its cheapest split position in `best`.
void sweep(SplitContext& ctx, const std::vector<PrimRef>& p, const NodeBounds& b, int axis, Best& best) {
    const auto n = static_cast<std::uint32_t>(p.size());
    auto& right_area = ctx.scratch.areas;
    right_area.resize(n);
    Aabb box;
    for (std::uint32_t i = n; i-- > 1;) {
        box.grow(p[i].box());
        right_area[i] = box.half_area();
    }
    box = Aabb{};
    const float inv_parent = SahCost::inverse_area(b.box.half_area());
    const SahCost sah(ctx.config);
    for (std::uint32_t i = 1; i < n; ++i) {  // left = [0, i), right = [i, n)
        box.grow(p[i - 1].box());
        const float cost = sah.split(inv_parent, box.half_area(), i, right_area[i], n - i);
        if (cost < best.cost) best = {cost, axis, i};
    }
}

}  // namespace

std::optional<Split> split_sweep_sah(SplitContext& ctx, Range r, int src, const NodeBounds& b, int axis) {
    const PrimRef* in = ctx.buffers[src];
    auto& sorted = ctx.scratch.sorted;
    Vec3 extent = b.centroids.extent();
    Best best;
    int sorted_axis = -1;
    for (int a = 0; a < 3; ++a) {
        if ((axis != kAllAxes && a != axis) || !(extent[a] > 0.0f)) continue;
        sort_on_axis(ctx, r, in, a);
        sorted_axis = a;
        sweep(ctx, sorted, b, a, best);
        // a top node's three sorts were the build's longest stretch without a stop check (2M
        // references, two threads: 3.1 s between the caller's progress calls; its sorts on the
        // pool poll between chunks now): the calling thread polls after each axis and, once a
        // stop is asked, splits on the axes swept so far (the tree is thrown away: the builder
        // stops at its next node; a worker has no `parallel`)
        if (ctx.parallel && ctx.parallel->while_waiting) {
            (*ctx.parallel->while_waiting)();
            if (best.axis >= 0 && ctx.parallel->cancel && ctx.parallel->cancel->stop_requested()) break;
        }
    }
    if (best.axis < 0) return std::nullopt;
    if (sorted_axis != best.axis) sort_on_axis(ctx, r, in, best.axis);
    std::copy(sorted.begin(), sorted.end(), ctx.buffers[1 - src] + r.begin);
    Split s = split_at(ctx, r, 1 - src, b, r.begin + best.mid);
    s.cost = best.cost;
    return s;
}

}  // namespace bvhlab
