// partition_avx2.cpp — the scatters and the bounds pass of partition.h for CPUs with AVX2
// (compiled with -mavx2, chosen at run time, isa.h): the same template and predicates as the
// portable path, each reference moved as one 256-bit load and store; bounds with one 256-bit
// `min` of (lo, -hi) per reference. The same comparisons, minima and (lane by lane, in the same
// order) sums as the portable code, so the same trees. See binning_avx2.cpp for why nothing here
// may call an inline function of another header (the predicates are in partition.h's unnamed
// namespace, so their instantiations here are this file's own).
#include <immintrin.h>

#include "partition.h"

namespace bvhlab::avx2 {
namespace {

/// Moves a reference as one 256-bit load and store (GCC's generic tuning would split a copy).
struct MoveYmm {
    static __m256 load(const PrimRef* p) { return _mm256_loadu_ps(reinterpret_cast<const float*>(p)); }
    static void store(PrimRef* p, __m256 v) { _mm256_storeu_ps(reinterpret_cast<float*>(p), v); }
};

/// TaggedLeft, eight tags at a time.
struct TaggedLeft8 {
    TaggedLeft one;
    __m128i last_left = _mm_set1_epi16(short(one.t.last_left));

    bool operator()(const PrimRef& p, std::uint32_t i) const { return one(p, i); }
    unsigned eight(const PrimRef*, std::uint32_t i) const {
        const __m128i tag = _mm_loadu_si128(reinterpret_cast<const __m128i*>(one.t.tag + (i - one.t.base)));
        const __m128i at_most = _mm_cmpeq_epi16(_mm_min_epu16(tag, last_left), tag);  // unsigned tag <= last_left
        return unsigned(_mm_movemask_epi8(_mm_packs_epi16(at_most, _mm_setzero_si128()))) & 0xffu;
    }
};

/// Running bounds: box as (lo, -hi) in one register, twice-centroid minima and maxima, sums.
struct Acc {
    __m256 box = _mm256_set1_ps(__builtin_inff());
    __m128 clo = _mm_set1_ps(__builtin_inff()), chi = _mm_set1_ps(-__builtin_inff());
    __m256d sum = _mm256_setzero_pd();
};

template <bool kSum>
inline void grow(Acc& a, const PrimRef* p, __m256 xyz, __m256 flip_hi) {
    const __m256 v = _mm256_and_ps(_mm256_loadu_ps(reinterpret_cast<const float*>(p)), xyz);
    a.box = _mm256_min_ps(a.box, _mm256_xor_ps(v, flip_hi));
    const __m128 c = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));  // twice the centroid
    a.clo = _mm_min_ps(a.clo, c), a.chi = _mm_max_ps(a.chi, c);
    if constexpr (kSum) a.sum = _mm256_add_pd(a.sum, _mm256_cvtps_pd(c));
}

template <bool kSum>
void run_bounds_impl(const PrimRef* refs, Range r, RunBounds& out) {
    const __m256 xyz = _mm256_castsi256_ps(_mm256_setr_epi32(-1, -1, -1, 0, -1, -1, -1, 0));
    const __m256 flip_hi = _mm256_setr_ps(0, 0, 0, 0, -0.0f, -0.0f, -0.0f, -0.0f);
    Acc even, odd;
    std::uint32_t i = r.begin;
    for (; i + 1 < r.end; i += 2) grow<kSum>(even, refs + i, xyz, flip_hi), grow<kSum>(odd, refs + i + 1, xyz, flip_hi);
    if (i < r.end) grow<kSum>(even, refs + i, xyz, flip_hi);
    // even grows by odd, as the portable merge does: minima, maxima, then sums
    const __m256 box = _mm256_min_ps(even.box, odd.box);
    const __m128 sign = _mm_set1_ps(-0.0f);
    _mm_store_ps(out.lo, _mm256_castps256_ps128(box));
    _mm_store_ps(out.hi, _mm_xor_ps(_mm256_extractf128_ps(box, 1), sign));
    _mm_store_ps(out.clo, _mm_min_ps(even.clo, odd.clo));
    _mm_store_ps(out.chi, _mm_max_ps(even.chi, odd.chi));
    _mm256_storeu_pd(out.sum, _mm256_add_pd(even.sum, odd.sum));
}

}  // namespace

std::uint32_t scatter_below(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                            int axis, float twice, bool contained) {
    const BelowTwice below{axis, twice};
    return contained ? scatter<true, MoveYmm>(src, dst, r, left, right, below)
                     : scatter<false, MoveYmm>(src, dst, r, left, right, below);
}

std::uint32_t scatter_tagged(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                             const SideTags& tags, bool contained) {
    const TaggedLeft8 below{{tags}};
    return contained ? scatter<true, MoveYmm>(src, dst, r, left, right, below)
                     : scatter<false, MoveYmm>(src, dst, r, left, right, below);
}

void run_bounds(const PrimRef* refs, Range r, bool with_sum, RunBounds& out) {
    with_sum ? run_bounds_impl<true>(refs, r, out) : run_bounds_impl<false>(refs, r, out);
}

void count_buckets(const PrimRef* src, Range r, const Bucketing& b, std::uint16_t* tag, std::uint32_t* count) {
    // Eight references at a time: the twice-centroids added one by one (vgatherdps is slower
    // here), then the bucket of all eight with the portable path's operations in its order
    // (sub, mul, max with 0, min with top, truncate).
    const __m256 origin = _mm256_set1_ps(b.origin), scale = _mm256_set1_ps(b.scale), top = _mm256_set1_ps(b.top);
    const __m256 zero = _mm256_setzero_ps();
    const std::uint32_t n = r.size();
    const int a = b.axis;
    std::uint32_t i = 0;
    alignas(32) std::uint32_t k[8];
    for (; i + 8 <= n; i += 8) {
        const PrimRef* p = src + r.begin + i;
        const __m256 c = _mm256_setr_ps(p[0].lo[a] + p[0].hi[a], p[1].lo[a] + p[1].hi[a], p[2].lo[a] + p[2].hi[a],
                                        p[3].lo[a] + p[3].hi[a], p[4].lo[a] + p[4].hi[a], p[5].lo[a] + p[5].hi[a],
                                        p[6].lo[a] + p[6].hi[a], p[7].lo[a] + p[7].hi[a]);
        const __m256 x = _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(c, origin), scale), zero), top);
        const __m256i bucket = _mm256_cvttps_epi32(x);
        _mm256_store_si256(reinterpret_cast<__m256i*>(k), bucket);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(tag + i),
                         _mm_packus_epi32(_mm256_castsi256_si128(bucket), _mm256_extracti128_si256(bucket, 1)));
        for (std::uint32_t j = 0; j < 8; ++j) ++count[k[j]];
    }
    for (; i < n; ++i) {
        const PrimRef& p = src[r.begin + i];
        float x = ((p.lo[b.axis] + p.hi[b.axis]) - b.origin) * b.scale;
        x = x > 0.0f ? x : 0.0f;
        x = x < b.top ? x : b.top;
        ++count[tag[i] = std::uint16_t(x)];
    }
}

}  // namespace bvhlab::avx2
