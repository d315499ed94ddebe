// Helpers shared by every split method: chunks for the top of the tree, bounds, the SAH cost of
// a split, partitioning at a position, the fallbacks.
#include <algorithm>
#include <limits>

#include "binning.h"
#include "bvhlab/isa.h"
#include "bvhlab/thread_pool.h"
#include "partition.h"

namespace bvhlab {

SplitScratch::SplitScratch() = default;
SplitScratch::~SplitScratch() = default;

std::uint32_t chunk_count(const SplitContext& ctx, Range r) {
    if (!ctx.parallel || r.size() < kMinParallelRange) return 1;
    // Several per thread for balance, and none larger than 2^16 references (a few milliseconds),
    // so that the calling thread checks for cancellation often enough.
    const std::uint32_t per_thread = ctx.parallel->threads < 2 ? 1 : 4 * ctx.parallel->threads;
    return std::max<std::uint32_t>(std::min<std::uint32_t>(per_thread, r.size() / (kMinParallelRange / 8)),
                                   (r.size() + 0xffffu) >> 16);
}

Range chunk_of(Range r, std::uint32_t k, std::uint32_t chunks) {
    const std::uint64_t n = r.size();
    return {r.begin + std::uint32_t(n * k / chunks), r.begin + std::uint32_t(n * (k + 1) / chunks)};
}

void for_each_chunk(const SplitContext& ctx, Range r, std::uint32_t chunks,
                    const std::function<void(std::uint32_t, Range)>& pass) {
    if (chunks == 1) return pass(0, r);
    if (!ctx.parallel || ctx.parallel->threads < 2) {  // in turn, polling the cancellation between chunks
        for (std::uint32_t k = 0; k < chunks; ++k) {
            pass(k, chunk_of(r, k, chunks));
            if (ctx.parallel && ctx.parallel->while_waiting) (*ctx.parallel->while_waiting)();
        }
        return;
    }
    const ParallelPasses& p = *ctx.parallel;
    ThreadPool::Task task = [&](std::size_t k, unsigned) {
        pass(std::uint32_t(k), chunk_of(r, std::uint32_t(k), chunks));
    };
    p.pool->run(chunks, p.threads, task, p.while_waiting ? *p.while_waiting : std::function<void()>());
}

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
/// Centroid sums are added in blocks of this many references from the start of the range, and
/// the block sums in order: the same rounding however many threads compute them.
constexpr std::uint32_t kSumBlock = 4096;

/// Running box, twice-centroid box and centroid sum of one run of references.
struct BoundsRun {
    F4 lo = F4::splat(kInf), hi = F4::splat(-kInf), clo = lo, chi = hi;
    double sum[3] = {0, 0, 0};

    template <bool kSum>
    void add(const PrimRef* refs, Range r) {
        for (std::uint32_t i = r.begin; i < r.end; ++i) {
            const F4 a = refs[i].lo4(), b = refs[i].hi4(), c = a + b;  // twice the centroid
            lo = min(lo, a), hi = max(hi, b), clo = min(clo, c), chi = max(chi, c);
            if constexpr (kSum)
                for (int k = 0; k < 3; ++k) sum[k] += 0.5 * double(refs[i].lo[k] + refs[i].hi[k]);
        }
    }
    void merge(const BoundsRun& o) {
        lo = min(lo, o.lo), hi = max(hi, o.hi), clo = min(clo, o.clo), chi = max(chi, o.chi);
        for (int k = 0; k < 3; ++k) sum[k] += o.sum[k];
    }
};

NodeBounds to_bounds(const BoundsRun& run, bool with_sum) {
    auto vec = [](F4 v) { return Vec3{v.lane(0), v.lane(1), v.lane(2)}; };
    const F4 half = F4::splat(0.5f);
    NodeBounds b{{vec(run.lo), vec(run.hi)}, {vec(run.clo * half), vec(run.chi * half)}};
    if (with_sum) std::copy(run.sum, run.sum + 3, b.centroid_sum), b.has_sum = true;
    return b;
}

}  // namespace

NodeBounds bounds_of(const SplitContext& ctx, Range r, int buf, bool with_sum) {
    const PrimRef* refs = ctx.buffers[buf];
    const std::uint32_t blocks = std::max<std::uint32_t>(1, (r.size() + kSumBlock - 1) / kSumBlock);
    if (blocks == 1) {
        BoundsRun run;
        with_sum ? run.add<true>(refs, r) : run.add<false>(refs, r);
        return to_bounds(run, with_sum);
    }
    std::vector<BoundsRun> runs(blocks);
    const std::uint32_t chunks = std::min(chunk_count(ctx, r), blocks);
    for_each_chunk(ctx, {0, blocks}, chunks, [&](std::uint32_t, Range bl) {
        for (std::uint32_t k = bl.begin; k < bl.end; ++k) {
            Range block{r.begin + k * kSumBlock, std::min(r.end, r.begin + (k + 1) * kSumBlock)};
            with_sum ? runs[k].add<true>(refs, block) : runs[k].add<false>(refs, block);
        }
    });
    for (std::uint32_t k = 1; k < blocks; ++k) runs[0].merge(runs[k]);
    return to_bounds(runs[0], with_sum);
}

#if defined(BVHLAB_AVX2_KERNELS)
namespace avx2 {  // partition_avx2.cpp
std::uint32_t scatter_below(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                            int axis, float twice, bool with_sum, SideBounds sides[2]);
}
#endif

std::uint32_t scatter_below(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                            int axis, float twice, bool with_sum, SideBounds sides[2]) {
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() == Isa::Avx2) return avx2::scatter_below(src, dst, r, left, right, axis, twice, with_sum, sides);
#endif
    auto below = [=](const PrimRef& p) { return p.lo[axis] + p.hi[axis] < twice; };
    return with_sum ? scatter<true>(src, dst, r, left, right, below, sides)
                    : scatter<false>(src, dst, r, left, right, below, sides);
}

NodeBounds SideBounds::finish(bool with_sum) const {
    auto vec = [](F4 v) { return Vec3{v.lane(0), v.lane(1), v.lane(2)}; };
    const F4 half = F4::splat(0.5f);
    NodeBounds b{{vec(lo), vec(hi)}, {vec(c_lo * half), vec(c_hi * half)}};
    if (with_sum) std::copy(sum, sum + 3, b.centroid_sum), b.has_sum = true;
    return b;
}

Split split_at(SplitContext& ctx, Range r, int buf, const NodeBounds& parent, std::uint32_t mid) {
    const bool sums = method_info(ctx.config.method).needs_centroid_sum;
    return split_with(ctx, r, buf, parent, mid, bounds_of(ctx, {r.begin, mid}, buf, sums),
                      bounds_of(ctx, {mid, r.end}, buf, sums));
}

Split split_with(SplitContext& ctx, Range r, int buf, const NodeBounds& parent, std::uint32_t mid,
                 const NodeBounds& left, const NodeBounds& right) {
    Split s;
    s.mid = mid;
    s.left = left, s.right = right;
    const SahCost sah(ctx.config);
    s.cost = sah.split(SahCost::inverse_area(parent.box.half_area()), s.left.box.half_area(), mid - r.begin,
                       s.right.box.half_area(), r.end - mid);
    s.buffer = static_cast<std::uint8_t>(buf);
    return s;
}

std::optional<Split> split_at_position(SplitContext& ctx, Range r, int src, const NodeBounds& parent, int axis,
                                       float position) {
    // Compare 2·centroid with 2·position: the same order without a multiply per reference.
    const float twice = 2.0f * position;
    const bool sums = method_info(ctx.config.method).needs_centroid_sum;
    SideBounds sides[2];
    const PrimRef* in = ctx.buffers[src];
    PrimRef* out = ctx.buffers[1 - src];
    auto run = [&](Range c, std::uint32_t left, std::uint32_t right, SideBounds* s) {
        return scatter_below(in, out, c, left, right, axis, twice, sums, s);
    };
    const std::uint32_t mid =
        partition_with(ctx, r, in, [=](const PrimRef& p) { return p.lo[axis] + p.hi[axis] < twice; }, run, sides);
    if (mid == r.begin || mid == r.end) return std::nullopt;
    return split_with(ctx, r, 1 - src, parent, mid, sides[0].finish(sums), sides[1].finish(sums));
}

Split split_even(SplitContext& ctx, Range r, int src, const NodeBounds& parent) {
    return split_at(ctx, r, src, parent, r.begin + r.size() / 2);
}

std::optional<Split> split_best_of_axes(SplitFunction split, SplitContext& ctx, Range r, int src, const NodeBounds& b) {
    std::optional<Split> best;
    int best_axis = -1, last_axis = -1;
    const Vec3 extent = b.centroids.extent();
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
