// binning_avx2.cpp — the passes of binning.h for CPUs with AVX2 (compiled with -mavx2, chosen at
// run time, see isa.h). One 256-bit `min` grows a bucket's (lo, -hi) box. The arithmetic is that
// of the portable passes, operation for operation, so the buckets, and so the trees, are the same.
//
// This file must not call inline functions of the other headers (F4's operators, PrimRef's
// members...): the linker keeps one copy of each inline function, and an AVX2 copy would then
// run on CPUs without AVX2. It reads their data and uses only the helpers below.
#include <immintrin.h>

#include "binning.h"

namespace bvhlab::avx2 {
namespace {

struct Kernel {
    const __m256 xyz = _mm256_castsi256_ps(_mm256_setr_epi32(-1, -1, -1, 0, -1, -1, -1, 0));
    const __m256 flip_hi = _mm256_setr_ps(0, 0, 0, 0, -0.0f, -0.0f, -0.0f, -0.0f);
    const __m128 zero = _mm_setzero_ps(), sign = _mm_set1_ps(-0.0f);
};

/// Bucket coordinate clamped to [0, top]: (c2 - origin2) · scale, max with 0 first (NaN → 0).
inline __m128 bucket_coordinate(__m128 c2, __m128 origin2, __m128 scale, __m128 top, __m128 zero) {
    return _mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(c2, origin2), scale), zero), top);
}

/// One copy of one node's buckets: the (lo, -hi) boxes of axis a start at box + a · box_stride
/// bytes, its counts at count + a · count_stride bytes.
struct Buckets {
    char* box = nullptr;
    char* count = nullptr;
    std::size_t box_stride = 0, count_stride = 0;

    Buckets() = default;
    explicit Buckets(const BinSet& b)
        : box(reinterpret_cast<char*>(b.box)),
          count(reinterpret_cast<char*>(b.count)),
          box_stride(32 * std::size_t(b.bins)),
          count_stride(4 * std::size_t(b.bins)) {}
    void add(__m128i k, __m256 box_of_ref) const {
        const std::size_t k0 = std::uint32_t(_mm_cvtsi128_si32(k)), k1 = std::uint32_t(_mm_extract_epi32(k, 1)),
                          k2 = std::uint32_t(_mm_extract_epi32(k, 2));
        float* b0 = reinterpret_cast<float*>(box + 32 * k0);
        float* b1 = reinterpret_cast<float*>(box + box_stride + 32 * k1);
        float* b2 = reinterpret_cast<float*>(box + 2 * box_stride + 32 * k2);
        _mm256_store_ps(b0, _mm256_min_ps(_mm256_load_ps(b0), box_of_ref));
        _mm256_store_ps(b1, _mm256_min_ps(_mm256_load_ps(b1), box_of_ref));
        _mm256_store_ps(b2, _mm256_min_ps(_mm256_load_ps(b2), box_of_ref));
        ++*reinterpret_cast<std::uint32_t*>(count + 4 * k0);
        ++*reinterpret_cast<std::uint32_t*>(count + count_stride + 4 * k1);
        ++*reinterpret_cast<std::uint32_t*>(count + 2 * count_stride + 4 * k2);
    }
};

/// What the fused pass needs of one child: its frame and two copies of its buckets (null: none).
struct Side {
    __m128 origin2, scale;
    const Buckets* copy;
};

}  // namespace

void bin_refs(const PrimRef* refs, Range r, const BinFrame& f, const BinSet copies[2]) {
    const Kernel c;
    const Buckets b[2] = {Buckets(copies[0]), Buckets(copies[1])};
    const __m128 origin2 = f.origin2.v, scale = f.scale.v, top = f.top.v;
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        const __m256 v = _mm256_and_ps(_mm256_loadu_ps(reinterpret_cast<const float*>(refs + i)), c.xyz);
        const __m128 c2 = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
        const __m128i k = _mm_cvttps_epi32(bucket_coordinate(c2, origin2, scale, top, c.zero));
        b[i & 1].add(k, _mm256_xor_ps(v, c.flip_hi));
    }
}

namespace {

template <bool kCentroids>
std::uint32_t partition_and_bin_impl(const PrimRef* __restrict src, PrimRef* __restrict dst, Range r,
                                     std::uint32_t left, std::uint32_t right, const BinFrame& parent,
                                     const BinSplit& split, const ChildBinning child[2], CentroidBounds sides[2]) {
    const Kernel c;
    Buckets buckets[2][2];
    Side side[2];
    for (int s = 0; s < 2; ++s) {
        side[s] = {child[s].frame.origin2.v, child[s].frame.scale.v, nullptr};
        if (!child[s].copies) continue;
        buckets[s][0] = Buckets(child[s].copies[0]), buckets[s][1] = Buckets(child[s].copies[1]);
        side[s].copy = buckets[s];
    }
    alignas(16) std::uint32_t lane[4] = {0, 0, 0, 0};
    lane[split.axis] = ~0u;
    const __m128 axis_lane = _mm_load_ps(reinterpret_cast<const float*>(lane));
    const __m128 origin2 = parent.origin2.v, scale = parent.scale.v, top = parent.top.v;
    const __m128 limit = _mm_set1_ps(float(split.last_left) + 1.0f);  // bucket <= last_left ⟺ x < last_left + 1
    // Twice-centroid (lo, -hi) per [copy][side]: even and odd references alternate, so that a run
    // going one way does not chain through one min.
    alignas(32) float acc[2][2][8];
    for (auto& copy : acc)
        for (auto& a : copy) _mm256_store_ps(a, _mm256_set1_ps(__builtin_inff()));
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        const __m256 raw = _mm256_loadu_ps(reinterpret_cast<const float*>(src + i));
        const __m256 v = _mm256_and_ps(raw, c.xyz);
        const __m128 c2 = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
        const __m128 x = bucket_coordinate(c2, origin2, scale, top, c.zero);
        const std::uint32_t l = _mm_movemask_ps(_mm_and_ps(_mm_cmplt_ps(x, limit), axis_lane)) != 0 ? 1u : 0u;
        const std::uint32_t mask = 0u - l;
        _mm256_storeu_ps(reinterpret_cast<float*>(dst + (((right - 1) & ~mask) | (left & mask))), raw);
        left += l;
        right -= 1u - l;
        if constexpr (kCentroids) {
            float* a = acc[i & 1][1 - l];
            const __m256 cc = _mm256_insertf128_ps(_mm256_castps128_ps256(c2), _mm_xor_ps(c2, c.sign), 1);
            _mm256_store_ps(a, _mm256_min_ps(_mm256_load_ps(a), cc));
        }
        const Side& t = side[1 - l];
        if (!t.copy) continue;
        const __m128i k = _mm_cvttps_epi32(bucket_coordinate(c2, t.origin2, t.scale, top, c.zero));
        t.copy[i & 1].add(k, _mm256_xor_ps(v, c.flip_hi));
    }
    for (int s = 0; s < 2 && kCentroids; ++s) {
        const __m256 both = _mm256_min_ps(_mm256_load_ps(acc[0][s]), _mm256_load_ps(acc[1][s]));
        sides[s].lo.v = _mm_min_ps(sides[s].lo.v, _mm256_castps256_ps128(both));
        sides[s].neg_hi.v = _mm_min_ps(sides[s].neg_hi.v, _mm256_extractf128_ps(both, 1));
    }
    return left;
}

}  // namespace

std::uint32_t partition_and_bin(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                                const BinFrame& parent, const BinSplit& split, const ChildBinning child[2],
                                CentroidBounds sides[2]) {
    return sides ? partition_and_bin_impl<true>(src, dst, r, left, right, parent, split, child, sides)
                 : partition_and_bin_impl<false>(src, dst, r, left, right, parent, split, child, sides);
}

}  // namespace bvhlab::avx2
