// Helpers shared by every split method: chunks for the top of the tree, bounds, the SAH cost of
// a split, partitioning at a position, the fallbacks.
#include <algorithm>
#include <cstddef>
#include <limits>
#if defined(__SSE4_1__)
#include <smmintrin.h>
#endif

#include "binning.h"
#include "bvhlab/isa.h"
#include "bvhlab/thread_pool.h"
#include "partition.h"

namespace bvhlab {

SplitScratch::SplitScratch() = default;
SplitScratch::~SplitScratch() = default;

std::uint32_t chunk_count(const SplitContext& ctx, Range r) {
    if (!ctx.parallel) return 1;
    const bool root = r.begin == 0 && r.size() == ctx.parallel->root_size;
    if (r.size() < (root ? kMinParallelRoot : kMinParallelRange)) return 1;
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
    std::vector<Range> ranges(chunks);
    for (std::uint32_t k = 0; k < chunks; ++k) ranges[k] = chunk_of(r, k, chunks);
    for_each_range(ctx, ranges, pass);
}

void for_each_range(const SplitContext& ctx, std::span<const Range> ranges,
                    const std::function<void(std::uint32_t, Range)>& pass) {
    const auto count = static_cast<std::uint32_t>(ranges.size());
    if (!ctx.parallel || ctx.parallel->threads < 2 || count < 2) {  // in turn, polling the cancellation after each
        for (std::uint32_t k = 0; k < count; ++k) {
            pass(k, ranges[k]);
            if (ctx.parallel && ctx.parallel->while_waiting) (*ctx.parallel->while_waiting)();
        }
        return;
    }
    // The pool hands out indices in order: the largest ranges first, so that none is left to
    // start last (ranges cut at the pieces of a pass before differ in size; see PieceCounts).
    std::vector<std::uint32_t> order(count);
    for (std::uint32_t k = 0; k < count; ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return ranges[a].size() > ranges[b].size(); });
    const ParallelPasses& p = *ctx.parallel;
    ThreadPool::Task task = [&](std::size_t i, unsigned) { pass(order[i], ranges[order[i]]); };
    p.pool->run(count, p.threads, task, p.while_waiting ? *p.while_waiting : std::function<void()>());
}

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
/// Bounds are gathered in blocks of this many references from the start of the range, and the
/// blocks merged in order: the same centroid sums however many threads compute them.
constexpr std::uint32_t kSumBlock = 4096;

/// Running bounds of a run: box, twice-centroid box, twice-centroid sums (x, y | z, 0).
struct BoundsAcc {
    F4 lo = F4::splat(kInf), hi = F4::splat(-kInf), clo = lo, chi = hi;
#ifdef BVHLAB_SSE
    __m128d xy = _mm_setzero_pd(), z0 = _mm_setzero_pd();
#else
    double s[4] = {0, 0, 0, 0};
#endif

    template <bool kSum>
    void grow(const PrimRef& p) {
        const F4 a = p.lo4(), b = p.hi4(), c = a + b;  // twice the centroid
        lo = min(lo, a), hi = max(hi, b), clo = min(clo, c), chi = max(chi, c);
        if constexpr (kSum) {
#ifdef BVHLAB_SSE
            xy = _mm_add_pd(xy, _mm_cvtps_pd(c.v)), z0 = _mm_add_pd(z0, _mm_cvtps_pd(_mm_movehl_ps(c.v, c.v)));
#else
            for (int k = 0; k < 4; ++k) s[k] += double(c.lane(k));
#endif
        }
    }
    void store(RunBounds& out) const {
        lo.store(out.lo), hi.store(out.hi), clo.store(out.clo), chi.store(out.chi);
#ifdef BVHLAB_SSE
        _mm_store_pd(out.sum, xy), _mm_store_pd(out.sum + 2, z0);
#else
        std::copy(s, s + 4, out.sum);
#endif
    }
};

/// a grows by b: the minima, maxima and sums of both, in this order.
void merge(RunBounds& a, const RunBounds& b) {
    min(F4::load(a.lo), F4::load(b.lo)).store(a.lo), max(F4::load(a.hi), F4::load(b.hi)).store(a.hi);
    min(F4::load(a.clo), F4::load(b.clo)).store(a.clo), max(F4::load(a.chi), F4::load(b.chi)).store(a.chi);
    for (int k = 0; k < 4; ++k) a.sum[k] += b.sum[k];
}

template <bool kSum>
void portable_run_bounds(const PrimRef* refs, Range r, RunBounds& out) {
    BoundsAcc even, odd;  // locals: kept in registers
    std::uint32_t i = r.begin;
    for (; i + 1 < r.end; i += 2) even.grow<kSum>(refs[i]), odd.grow<kSum>(refs[i + 1]);
    if (i < r.end) even.grow<kSum>(refs[i]);
    RunBounds o;
    even.store(out), odd.store(o);
    merge(out, o);
}

/// Writes the bounds of `run` into b, in place.
void write_bounds(const RunBounds& run, bool with_sum, NodeBounds& b) {
#if defined(__SSE4_1__)
    // The five 16-byte chunks of NodeBounds, each written by one store: the copies that follow
    // (into Split, WorkItem, the work stack) read 16 bytes at a time, and a load that spans
    // several narrower stores waits for them to retire (no store-to-load forwarding), which on
    // Sponza cost more than the bounds pass itself.
    static_assert(sizeof(NodeBounds) == 80 && alignof(NodeBounds) == 16 && offsetof(NodeBounds, centroids) == 24 &&
                  offsetof(NodeBounds, centroid_sum) == 48 && offsetof(NodeBounds, has_sum) == 72 &&
                  offsetof(NodeBounds, bins) == 76);
    const __m128 half = _mm_set1_ps(0.5f);
    const __m128 lo = _mm_load_ps(run.lo), hi = _mm_load_ps(run.hi);
    const __m128 clo = _mm_mul_ps(_mm_load_ps(run.clo), half), chi = _mm_mul_ps(_mm_load_ps(run.chi), half);
    const __m128 shifted_chi = _mm_castsi128_ps(_mm_slli_si128(_mm_castps_si128(chi), 4));  // 0, x, y, z
    auto* chunk = reinterpret_cast<char*>(&b);
    _mm_store_ps(reinterpret_cast<float*>(chunk), _mm_blend_ps(lo, _mm_shuffle_ps(hi, hi, 0), 0b1000));
    _mm_store_ps(reinterpret_cast<float*>(chunk + 16), _mm_shuffle_ps(hi, clo, _MM_SHUFFLE(1, 0, 2, 1)));
    _mm_store_ps(reinterpret_cast<float*>(chunk + 32),
                 _mm_blend_ps(shifted_chi, _mm_shuffle_ps(clo, clo, _MM_SHUFFLE(2, 2, 2, 2)), 0b0001));
    const __m128d half_sum = _mm_set1_pd(0.5);  // exact: sums of twice the centroids
    const __m128d keep = _mm_castsi128_pd(_mm_set1_epi32(with_sum ? -1 : 0));
    _mm_store_pd(reinterpret_cast<double*>(chunk + 48), _mm_and_pd(_mm_mul_pd(_mm_loadu_pd(run.sum), half_sum), keep));
    __m128i tail = _mm_castpd_si128(_mm_and_pd(_mm_mul_sd(_mm_load_sd(run.sum + 2), half_sum), keep));
    tail = _mm_insert_epi32(_mm_insert_epi32(tail, with_sum ? 1 : 0, 2), NodeBounds{}.bins, 3);  // has_sum, bins
    _mm_store_si128(reinterpret_cast<__m128i*>(chunk + 64), tail);
#else
    const float half = 0.5f;
    b = NodeBounds{};
    b.box = {{run.lo[0], run.lo[1], run.lo[2]}, {run.hi[0], run.hi[1], run.hi[2]}};
    b.centroids = {{run.clo[0] * half, run.clo[1] * half, run.clo[2] * half},
                   {run.chi[0] * half, run.chi[1] * half, run.chi[2] * half}};
    if (with_sum) {
        for (int k = 0; k < 3; ++k) b.centroid_sum[k] = 0.5 * run.sum[k];  // exact: sums of twice the centroids
        b.has_sum = true;
    }
#endif
}

/// bounds_of, written into b in place.
void bounds_into(const SplitContext& ctx, Range r, int buf, bool with_sum, NodeBounds& b) {
    const PrimRef* refs = ctx.buffers[buf];
    const std::uint32_t blocks = std::max<std::uint32_t>(1, (r.size() + kSumBlock - 1) / kSumBlock);
    RunBounds first;
    if (blocks == 1) {
        run_bounds(refs, r, with_sum, first);
        return write_bounds(first, with_sum, b);
    }
    std::vector<RunBounds> runs(blocks);
    const std::uint32_t chunks = std::min(chunk_count(ctx, r), blocks);
    for_each_chunk(ctx, {0, blocks}, chunks, [&](std::uint32_t, Range bl) {
        for (std::uint32_t k = bl.begin; k < bl.end; ++k)
            run_bounds(refs, {r.begin + k * kSumBlock, std::min(r.end, r.begin + (k + 1) * kSumBlock)}, with_sum,
                       runs[k]);
    });
    for (std::uint32_t k = 1; k < blocks; ++k) merge(runs[0], runs[k]);
    write_bounds(runs[0], with_sum, b);
}

/// s becomes the split at `mid` of r in buffer buf: both sides' bounds written in place, the cost.
/// (Split and NodeBounds are filled where they live, never assembled and copied: see write_bounds.)
void fill_split(SplitContext& ctx, Range r, int buf, const NodeBounds& parent, std::uint32_t mid, Split& s) {
    const bool sums = method_info(ctx.config.method).needs_centroid_sum;
    bounds_into(ctx, {r.begin, mid}, buf, sums, s.left);
    bounds_into(ctx, {mid, r.end}, buf, sums, s.right);
    s.mid = mid;
    s.cost = SahCost(ctx.config)
                 .split(SahCost::inverse_area(parent.box.half_area()), s.left.box.half_area(), mid - r.begin,
                        s.right.box.half_area(), r.end - mid);
    s.buffer = static_cast<std::uint8_t>(buf);
    s.leaf = false;
}

}  // namespace

#if defined(BVHLAB_AVX2_KERNELS)
namespace avx2 {  // partition_avx2.cpp
void run_bounds(const PrimRef* refs, Range r, bool with_sum, RunBounds& out);
}
#endif

void run_bounds(const PrimRef* refs, Range r, bool with_sum, RunBounds& out) {
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() >= Isa::Avx2) return avx2::run_bounds(refs, r, with_sum, out);
#endif
    with_sum ? portable_run_bounds<true>(refs, r, out) : portable_run_bounds<false>(refs, r, out);
}

NodeBounds bounds_of(const SplitContext& ctx, Range r, int buf, bool with_sum) {
    NodeBounds b;
    bounds_into(ctx, r, buf, with_sum, b);
    return b;
}

#if defined(BVHLAB_AVX2_KERNELS)
namespace avx2 {  // partition_avx2.cpp
std::uint32_t scatter_below(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                            int axis, float twice, bool contained);
std::uint32_t scatter_tagged(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                             const SideTags& tags, bool contained);
}  // namespace avx2
#endif

std::uint32_t scatter_below(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                            int axis, float twice, bool contained) {
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() >= Isa::Avx2) return avx2::scatter_below(src, dst, r, left, right, axis, twice, contained);
#endif
    const BelowTwice below{axis, twice};
    return contained ? scatter<true, MoveBytes>(src, dst, r, left, right, below)
                     : scatter<false, MoveBytes>(src, dst, r, left, right, below);
}

std::uint32_t scatter_tagged(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                             const SideTags& tags, bool contained) {
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() >= Isa::Avx2) return avx2::scatter_tagged(src, dst, r, left, right, tags, contained);
#endif
    const TaggedLeft below{tags};
    return contained ? scatter<true, MoveBytes>(src, dst, r, left, right, below)
                     : scatter<false, MoveBytes>(src, dst, r, left, right, below);
}

Split split_at(SplitContext& ctx, Range r, int buf, const NodeBounds& parent, std::uint32_t mid) {
    Split s;
    fill_split(ctx, r, buf, parent, mid, s);
    return s;
}

std::optional<Split> split_at_position(SplitContext& ctx, Range r, int src, const NodeBounds& parent, int axis,
                                       float position) {
    // Compare 2·centroid with 2·position: the same order without a multiply per reference.
    const float twice = 2.0f * position;
    const PrimRef* in = ctx.buffers[src];
    PrimRef* out = ctx.buffers[1 - src];
    auto run = [&](Range c, std::uint32_t left, std::uint32_t right, bool contained) {
        return scatter_below(in, out, c, left, right, axis, twice, contained);
    };
    const std::uint32_t mid = partition_with(ctx, r, in, BelowTwice{axis, twice}, run);
    std::optional<Split> s;  // one object from here to the caller: filled in place, never copied
    if (mid != r.begin && mid != r.end) fill_split(ctx, r, 1 - src, parent, mid, s.emplace());
    return s;
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
