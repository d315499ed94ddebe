// partition_avx2.cpp — scatter_below (partition.h) for CPUs with AVX2 (compiled with -mavx2,
// chosen at run time, isa.h): each reference moves as one 256-bit load and store, and each side's
// box and twice-centroid box grow by one 256-bit `min` of (lo, -hi). The same comparisons,
// minima and (in input order) centroid sums as the portable scatter, so the same splits. See
// binning_avx2.cpp for why nothing here may call an inline function of another header.
#include <immintrin.h>

#include "partition.h"

namespace bvhlab::avx2 {
namespace {

template <bool kSum>
std::uint32_t scatter_below_impl(const PrimRef* __restrict src, PrimRef* __restrict dst, Range r, std::uint32_t left,
                                 std::uint32_t right, int axis, float twice, SideBounds sides[2]) {
    const __m256 xyz = _mm256_castsi256_ps(_mm256_setr_epi32(-1, -1, -1, 0, -1, -1, -1, 0));
    const __m256 flip_hi = _mm256_setr_ps(0, 0, 0, 0, -0.0f, -0.0f, -0.0f, -0.0f);
    const __m128 sign = _mm_set1_ps(-0.0f);
    const __m256d neg_zero = _mm256_set1_pd(-0.0), half = _mm256_set1_pd(0.5);
    // per [copy][side]: box (lo, -hi), twice-centroid box (lo, -hi); even and odd references alternate
    alignas(32) float acc[2][2][2][8];
    for (auto& copy : acc)
        for (auto& side : copy)
            for (auto& a : side) _mm256_store_ps(a, _mm256_set1_ps(__builtin_inff()));
    __m256d sum[2] = {_mm256_setr_pd(sides[0].sum[0], sides[0].sum[1], sides[0].sum[2], 0.0),
                      _mm256_setr_pd(sides[1].sum[0], sides[1].sum[1], sides[1].sum[2], 0.0)};
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        const float* p = reinterpret_cast<const float*>(src + i);
        const std::uint32_t l = p[axis] + p[4 + axis] < twice ? 1u : 0u;  // the portable predicate
        const __m256 raw = _mm256_loadu_ps(p);
        const std::uint32_t mask = 0u - l;
        _mm256_storeu_ps(reinterpret_cast<float*>(dst + (((right - 1) & ~mask) | (left & mask))), raw);
        left += l;
        right -= 1u - l;
        const __m256 v = _mm256_and_ps(raw, xyz);
        const __m128 c2 = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
        float(*a)[8] = acc[i & 1][1 - l];
        _mm256_store_ps(a[0], _mm256_min_ps(_mm256_load_ps(a[0]), _mm256_xor_ps(v, flip_hi)));
        const __m256 cc = _mm256_insertf128_ps(_mm256_castps128_ps256(c2), _mm_xor_ps(c2, sign), 1);
        _mm256_store_ps(a[1], _mm256_min_ps(_mm256_load_ps(a[1]), cc));
        if constexpr (kSum) {  // in input order, adding -0 (which changes nothing) on the other side
            const __m256d s = _mm256_mul_pd(_mm256_cvtps_pd(c2), half);
            const __m256d goes_left = _mm256_castsi256_pd(_mm256_set1_epi64x(-std::int64_t(l)));
            sum[0] = _mm256_add_pd(sum[0], _mm256_blendv_pd(neg_zero, s, goes_left));
            sum[1] = _mm256_add_pd(sum[1], _mm256_blendv_pd(s, neg_zero, goes_left));
        }
    }
    for (int s = 0; s < 2; ++s) {
        const __m256 box = _mm256_min_ps(_mm256_load_ps(acc[0][s][0]), _mm256_load_ps(acc[1][s][0]));
        const __m256 cen = _mm256_min_ps(_mm256_load_ps(acc[0][s][1]), _mm256_load_ps(acc[1][s][1]));
        sides[s].lo.v = _mm_min_ps(sides[s].lo.v, _mm256_castps256_ps128(box));
        sides[s].hi.v = _mm_max_ps(sides[s].hi.v, _mm_xor_ps(_mm256_extractf128_ps(box, 1), sign));
        sides[s].c_lo.v = _mm_min_ps(sides[s].c_lo.v, _mm256_castps256_ps128(cen));
        sides[s].c_hi.v = _mm_max_ps(sides[s].c_hi.v, _mm_xor_ps(_mm256_extractf128_ps(cen, 1), sign));
        if (!kSum) continue;
        alignas(32) double out[4];
        _mm256_store_pd(out, sum[s]);
        sides[s].sum[0] = out[0], sides[s].sum[1] = out[1], sides[s].sum[2] = out[2];
    }
    return left;
}

}  // namespace

std::uint32_t scatter_below(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                            int axis, float twice, bool with_sum, SideBounds sides[2]) {
    return with_sum ? scatter_below_impl<true>(src, dst, r, left, right, axis, twice, sides)
                    : scatter_below_impl<false>(src, dst, r, left, right, axis, twice, sides);
}

}  // namespace bvhlab::avx2
