// Median split (report §2.3.1, PBRT "EqualCounts"): the ⌊n/2⌋ references first in the order
// (twice-centroid on the axis, position in the range) go left, in O(n) — never a sort. The
// order is total, so ties between equal centroids are broken by position and the split is the
// same on every path. A histogram of the centroids finds the bucket that holds the median; only
// that bucket's references are ranked exactly (std::nth_element, the report's
// select_nth_unstable, on 8-byte keys rather than 32-byte references); one branch-free scatter
// then moves every reference once, each side in input order, and the sides' bounds follow.
#include <algorithm>
#include <bit>
#include <cmath>

#include "bvhlab/isa.h"
#include "bvhlab/simd.h"
#include "bvhlab/split.h"
#include "partition.h"

namespace bvhlab {
namespace {

/// Ranges smaller than this rank every reference (split_small); a histogram would cost more.
constexpr std::uint32_t kDirectSelect = 16;

/// An unsigned key in the order of the floats (-0 taken as +0, as `<` and `==` take it).
std::uint64_t order_key(float x) {
    const auto bits = std::bit_cast<std::uint32_t>(x + 0.0f);
    return bits ^ (std::uint32_t(std::int32_t(bits) >> 31) | 0x80000000u);
}

/// The rank key of the reference at offset i of the range: twice-centroid first, then i.
std::uint64_t rank_key(const PrimRef& p, int axis, std::uint32_t i) {
    return order_key(p.lo[axis] + p.hi[axis]) << 32 | i;
}

/// The histogram bucket holding the median, and how many references lie in the buckets below.
struct MedianBucket {
    std::uint32_t bucket, below;
};

/// Tags each reference of the range with its bucket (monotone in the centroid: a lower bucket
/// never holds a larger centroid) and finds the median's.
MedianBucket tag_buckets(SplitContext& ctx, const PrimRef* in, Range r, const NodeBounds& b, int axis) {
    auto& tag = ctx.scratch.bucket;
    if (tag.size() < r.size()) tag.resize(r.size());  // never shrunk: no zeroing at every node
    const std::uint32_t buckets = std::min<std::uint32_t>(1024, r.size() / 4);
    const float extent = b.centroids.extent()[axis];
    const float scale = extent > 0 ? float(buckets) / (2.0f * extent) : 0.0f;
    const Bucketing bucketing{2.0f * b.centroids.lo[axis], std::isfinite(scale) ? scale : 0.0f, float(buckets - 1),
                              axis};
    auto& count = ctx.scratch.counts;
    count.assign(buckets, 0);
    count_buckets(in, r, bucketing, tag.data(), count.data());
    MedianBucket m{0, 0};
    while (m.below + count[m.bucket] <= r.size() / 2) m.below += count[m.bucket++];
    return m;
}

/// Appends to `out` the offsets i < n with tag[i] == bucket, in order; returns the new end. The
/// median's bucket holds few references of a large range: eight tags are compared at once and
/// only the matches are written (one store per tag before: a chain through the cursor that took
/// a quarter of split_median's time).
template <class It>
It collect_bucket(const std::uint16_t* tag, std::uint32_t n, std::uint16_t bucket, It out) {
    std::uint32_t i = 0;
#ifdef BVHLAB_SSE
    const __m128i want = _mm_set1_epi16(short(bucket));
    for (; i + 8 <= n; i += 8) {
        const __m128i eq = _mm_cmpeq_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(tag + i)), want);
        for (auto bits = unsigned(_mm_movemask_epi8(_mm_packs_epi16(eq, _mm_setzero_si128()))); bits; bits &= bits - 1)
            *out++ = i + std::uint32_t(__builtin_ctz(bits));
    }
#endif
    for (; i < n; ++i) *out = i, out += tag[i] == bucket;  // no branch to mispredict
    return out;
}

/// A range below kDirectSelect (three in four nodes of a median tree): each reference's rank
/// counted, and the scatter that partition.h's scatter() performs — the left side forward in
/// input order, the right side backward from the end — written out here, without the tags, the
/// selection and the dispatch a large range needs. Each reference is stored at both cursors and
/// one cursor moves (no branch): the slot written in vain is filled by a later reference.
std::optional<Split> split_small(SplitContext& ctx, Range r, int src, const NodeBounds& b, int axis) {
    const PrimRef* in = ctx.buffers[src] + r.begin;
    PrimRef* out = ctx.buffers[1 - src];
    const std::uint32_t n = r.size(), half = n / 2;
    std::uint32_t key[kDirectSelect];
    for (std::uint32_t i = 0; i < n; ++i) key[i] = std::uint32_t(order_key(in[i].lo[axis] + in[i].hi[axis]));
    std::uint32_t left = r.begin, right = r.end;
    for (std::uint32_t i = 0; i < n; ++i) {
        std::uint32_t rank = 0;  // the order of rank_key: centroid, then position
        for (std::uint32_t j = 0; j < i; ++j) rank += key[j] <= key[i];
        for (std::uint32_t j = i + 1; j < n; ++j) rank += key[j] < key[i];
        out[left] = in[i], out[right - 1] = in[i];
        const bool goes_left = rank < half;
        left += goes_left, right -= !goes_left;
    }
    return split_at(ctx, r, 1 - src, b, left);
}

/// Tags as `upper` the keys of rank `keep` and above among keys[0, n) (distinct: each holds its
/// offset in the low half), the offsets being those low halves. A few keys (the usual median
/// bucket) are ranked by counting, without branches; the introselect's insertion sort
/// mispredicted on most of its comparisons.
void tag_upper(std::uint64_t* keys, std::uint32_t n, std::uint32_t keep, std::uint16_t upper, std::uint16_t* tag) {
    if (n <= 32) {
        for (std::uint32_t a = 0; a < n; ++a) {
            std::uint32_t rank = 0;
            for (std::uint32_t b = 0; b < n; ++b) rank += keys[b] < keys[a];
            if (rank >= keep) tag[std::uint32_t(keys[a])] = upper;
        }
        return;
    }
    std::nth_element(keys, keys + keep, keys + n);
    for (std::uint32_t k = keep; k < n; ++k) tag[std::uint32_t(keys[k])] = upper;
}

}  // namespace

#if defined(BVHLAB_AVX2_KERNELS)
namespace avx2 {  // partition_avx2.cpp
void count_buckets(const PrimRef* src, Range r, const Bucketing& b, std::uint16_t* tag, std::uint32_t* count);
}
#endif

void count_buckets(const PrimRef* src, Range r, const Bucketing& b, std::uint16_t* tag, std::uint32_t* count) {
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() >= Isa::Avx2) return avx2::count_buckets(src, r, b, tag, count);
#endif
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        const PrimRef& p = src[i];
        ++count[tag[i - r.begin] =
                    std::uint16_t(truncate_clamped(((p.lo[b.axis] + p.hi[b.axis]) - b.origin) * b.scale, b.top))];
    }
}

std::optional<Split> split_median(SplitContext& ctx, Range r, int src, const NodeBounds& b, int axis) {
    if (r.size() < kDirectSelect) return split_small(ctx, r, src, b, axis);
    const PrimRef* in = ctx.buffers[src];
    PrimRef* out = ctx.buffers[1 - src];
    const MedianBucket m = tag_buckets(ctx, in, r, b, axis);
    // Rank the median's bucket exactly; its upper part is tagged as the next bucket (right).
    auto& tag = ctx.scratch.bucket;
    auto& ranks = ctx.scratch.ranks;
    if (ranks.size() < r.size()) ranks.resize(r.size());  // never shrunk: no zeroing at every node
    const auto first = ranks.begin(), last = collect_bucket(tag.data(), r.size(), std::uint16_t(m.bucket), first);
    for (auto k = first; k != last; ++k) *k = rank_key(in[r.begin + std::uint32_t(*k)], axis, std::uint32_t(*k));
    tag_upper(&*first, std::uint32_t(last - first), r.size() / 2 - m.below, std::uint16_t(m.bucket + 1), tag.data());

    const SideTags tags{tag.data(), r.begin, m.bucket};
    auto run = [&](Range c, std::uint32_t left, std::uint32_t right, bool contained) {
        return scatter_tagged(in, out, c, left, right, tags, contained);
    };
    const std::uint32_t mid = partition_with(ctx, r, in, TaggedLeft{tags}, run);
    return split_at(ctx, r, 1 - src, b, mid);  // mid = r.begin + ⌊n/2⌋
}

}  // namespace bvhlab
