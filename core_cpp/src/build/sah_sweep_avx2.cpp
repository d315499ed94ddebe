// sah_sweep_avx2.cpp — the three-axes SAH sweeps (sah_sweep.h: the buckets' cheapest_bin_cuts and
// the small-subtree builder's exact sweep) and the small-subtree builder's sort, for CPUs with
// AVX2. A box is one 256-bit (lo, -hi) register, so a step grows it with one `min` instead of
// two; the suffix pass keeps the right boxes instead of their areas, and the prefix pass then
// takes the areas of a candidate's left and right boxes together, one in each half of the
// registers (AxisBoxes::half_areas's operations, lane for lane). The sort compares two
// references at once. Same costs and orders, bit for bit, so the same trees. Calls no inline
// function of the other headers (see binning_avx2.cpp).
#include <immintrin.h>

#include <cstring>

#include "binning.h"
#include "bvhlab/split.h"
#include "sah_sweep_avx2.h"

namespace bvhlab::avx2 {
namespace {

constexpr float kInf = __builtin_inff();

/// [left | right] of one axis's two boxes: extents max(-(-hi) - lo, 0), x, y, z in lanes 0-2 of
/// each half.
inline __m256 extents(__m256 left, __m256 right, __m256 sign, __m256 zero) {
    const __m256 lo = _mm256_permute2f128_ps(left, right, 0x20), neg_hi = _mm256_permute2f128_ps(left, right, 0x31);
    return _mm256_max_ps(_mm256_sub_ps(_mm256_xor_ps(neg_hi, sign), lo), zero);
}

/// Half areas of the three axes' boxes, lane a of each half for axis a: transpose3 and
/// (x·y + y·z) + z·x, as AxisBoxes::half_areas, in each 128-bit half.
inline __m256 half_areas(__m256 e0, __m256 e1, __m256 e2, __m256 zero) {
    const __m256 ab_lo = _mm256_unpacklo_ps(e0, e1), cd_lo = _mm256_unpacklo_ps(e2, zero);
    const __m256 ab_hi = _mm256_unpackhi_ps(e0, e1), cd_hi = _mm256_unpackhi_ps(e2, zero);
    const auto pd = [](__m256 v) { return _mm256_castps_pd(v); };
    const __m256 x = _mm256_castpd_ps(_mm256_unpacklo_pd(pd(ab_lo), pd(cd_lo)));  // movelh
    const __m256 y = _mm256_castpd_ps(_mm256_unpackhi_pd(pd(ab_lo), pd(cd_lo)));  // movehl
    const __m256 z = _mm256_castpd_ps(_mm256_unpacklo_pd(pd(ab_hi), pd(cd_hi)));
    return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, y), _mm256_mul_ps(y, z)), _mm256_mul_ps(z, x));
}

/// The suffix pass: right[c][a] is the union of axis a's records c + 1 .. count - 1 (record(a, j)
/// gives record j of axis a's sequence, 32 bytes of (lo, -hi)).
template <class Record>
void right_boxes(const Record& record, std::uint32_t count, __m256 (*right)[3]) {
    __m256 b0 = _mm256_set1_ps(kInf), b1 = b0, b2 = b0;
    for (std::uint32_t j = count - 1; j > 0; --j) {
        b0 = _mm256_min_ps(b0, _mm256_load_ps(record(0, j))), b1 = _mm256_min_ps(b1, _mm256_load_ps(record(1, j)));
        b2 = _mm256_min_ps(b2, _mm256_load_ps(record(2, j)));
        right[j - 1][0] = b0, right[j - 1][1] = b1, right[j - 1][2] = b2;
    }
}

/// The prefix pass, a candidate at a time: the left boxes grown by the candidate's records, the
/// candidate priced as LaneSplitCost prices it and kept as LaneMin keeps one (sah_sweep.h), the
/// operations of both in their order, lane a for axis a.
class PrefixSweep {
public:
    explicit PrefixSweep(const SweepPrice& price)
        : trav_(_mm_set1_ps(price.traversal)),
          isect_(_mm_set1_ps(price.intersection)),
          inv_(_mm_set1_ps(price.inv_area)),
          by_area_(price.inv_area > 0.0f) {
        box_[0] = box_[1] = box_[2] = _mm256_set1_ps(kInf);
    }

    /// Grows the left boxes by the records x, y, z (one per axis) and offers the candidate whose
    /// right boxes are `right`, with the counts as SahCost::counted has them (floats), keyed
    /// `key`, in the lanes of `allowed`. `total()`, the counts' sum as floats, is read only for a
    /// parent of zero area.
    template <class Total>
    void offer(const float* x, const float* y, const float* z, const __m256 right[3], __m128 n_left, __m128 n_right,
               const Total& total, float key, __m128 allowed) {
        box_[0] = _mm256_min_ps(box_[0], _mm256_load_ps(x)), box_[1] = _mm256_min_ps(box_[1], _mm256_load_ps(y));
        box_[2] = _mm256_min_ps(box_[2], _mm256_load_ps(z));
        const __m256 zero = _mm256_setzero_ps(), sign = _mm256_set1_ps(-0.0f);
        const __m256 areas = half_areas(extents(box_[0], right[0], sign, zero), extents(box_[1], right[1], sign, zero),
                                        extents(box_[2], right[2], sign, zero), zero);  // [left | right]
        __m128 ratio;
        if (by_area_) {
            const __m256 weighted = _mm256_mul_ps(areas, _mm256_set_m128(n_right, n_left));
            ratio = _mm_mul_ps(_mm_add_ps(_mm256_castps256_ps128(weighted), _mm256_extractf128_ps(weighted, 1)), inv_);
        } else {
            ratio = total();
        }
        const __m128 cost = _mm_add_ps(trav_, _mm_mul_ps(ratio, isect_));
        const __m128 taken = _mm_and_ps(_mm_cmplt_ps(cost, best_), allowed);  // strictly cheaper: ties keep the first
        best_ = _mm_blendv_ps(best_, cost, taken), key_ = _mm_blendv_ps(key_, _mm_set1_ps(key), taken);
    }
    void store(float cost[4], float key[4]) const { _mm_storeu_ps(cost, best_), _mm_storeu_ps(key, key_); }

private:
    __m256 box_[3];
    const __m128 trav_, isect_, inv_;
    const bool by_area_;
    __m128 best_ = _mm_set1_ps(kInf), key_ = _mm_setzero_ps();
};

/// A bucket's count (Bucket::count: the bits of lo's lane 3 less kCountBias).
inline std::uint32_t count_of(const Bucket& b) {
    std::uint32_t bits;
    std::memcpy(&bits, reinterpret_cast<const char*>(&b) + 12, sizeof(bits));
    return bits - Bucket::kCountBias;
}

}  // namespace

void bucket_sweep(const Bucket* bucket, std::uint32_t bins, const SweepPrice& price, float cost_out[4],
                  float key_out[4]) {
    const float* base = reinterpret_cast<const float*>(bucket);
    const auto record = [&](int axis, std::uint32_t j) { return base + 8 * (std::size_t(axis) * bins + j); };
    const auto counts = [&](std::uint32_t j) {  // bucket j's count on each axis
        return _mm_setr_epi32(int(count_of(bucket[j])), int(count_of(bucket[bins + j])),
                              int(count_of(bucket[2 * std::size_t(bins) + j])), 0);
    };
    __m256 right[kMaxBins][3];  // candidate c: the buckets [c + 1, bins) of each axis
    right_boxes(record, bins, right);
    alignas(16) std::uint32_t right_n[kMaxBins][4];
    __m128i n = _mm_setzero_si128();
    for (std::uint32_t j = bins - 1; j > 0; --j)
        _mm_store_si128(reinterpret_cast<__m128i*>(right_n[j - 1]), n = _mm_add_epi32(n, counts(j)));
    // SahCost::counted under the parent, which holds every reference of each axis's buckets
    const __m128i mask = _mm_set1_epi32(int(price.mask)), keep = _mm_set1_epi32(int(~price.mask));
    const auto counted = [&](__m128i v) { return _mm_and_si128(_mm_add_epi32(v, mask), keep); };
    const __m128 zero = _mm_setzero_ps();
    PrefixSweep sweep(price);  // among candidates with both sides non-empty
    n = _mm_setzero_si128();
    for (std::uint32_t c = 0; c + 1 < bins; ++c) {
        n = _mm_add_epi32(n, counts(c));
        const __m128i left_n = counted(n),
                      right_c = counted(_mm_load_si128(reinterpret_cast<const __m128i*>(right_n[c])));
        const __m128 n_left = _mm_cvtepi32_ps(left_n), n_right = _mm_cvtepi32_ps(right_c);
        sweep.offer(
            record(0, c), record(1, c), record(2, c), right[c], n_left, n_right,
            [&] { return _mm_cvtepi32_ps(_mm_add_epi32(left_n, right_c)); }, float(c),
            _mm_and_ps(_mm_cmplt_ps(zero, n_left), _mm_cmplt_ps(zero, n_right)));
    }
    sweep.store(cost_out, key_out);
}

void small_ranks(const float* c2, std::uint32_t n, std::uint8_t (*order)[kSmallSubtree]) {
    const __m256 one = _mm256_set1_ps(1.0f);
    const __m128 one4 = _mm_set1_ps(1.0f);
    const auto at = [&](std::uint32_t j) { return _mm256_loadu_ps(c2 + 4 * std::size_t(j)); };  // j and j + 1
    for (std::uint32_t i = 0; i < n; ++i) {
        const __m128 ci4 = _mm_loadu_ps(c2 + 4 * std::size_t(i));
        const __m256 ci = _mm256_set_m128(ci4, ci4);
        // Counts of whole numbers: exact in any order, so pairs and halves may be summed as they come.
        __m256 before = _mm256_setzero_ps(), after = before;
        std::uint32_t j = 0;
        for (; j + 2 <= i; j += 2)
            before = _mm256_add_ps(before, _mm256_and_ps(_mm256_cmp_ps(at(j), ci, _CMP_LE_OQ), one));
        __m128 rank = _mm_add_ps(_mm256_castps256_ps128(before), _mm256_extractf128_ps(before, 1));
        if (j < i) rank = _mm_add_ps(rank, _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(c2 + 4 * std::size_t(j)), ci4), one4));
        for (j = i + 1; j + 2 <= n; j += 2)
            after = _mm256_add_ps(after, _mm256_and_ps(_mm256_cmp_ps(at(j), ci, _CMP_LT_OQ), one));
        rank = _mm_add_ps(rank, _mm_add_ps(_mm256_castps256_ps128(after), _mm256_extractf128_ps(after, 1)));
        if (j < n) rank = _mm_add_ps(rank, _mm_and_ps(_mm_cmplt_ps(_mm_loadu_ps(c2 + 4 * std::size_t(j)), ci4), one4));
        alignas(16) std::uint32_t r[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(r), _mm_cvttps_epi32(rank));
        for (int a = 0; a < 3; ++a) order[a][r[a]] = std::uint8_t(i);
    }
}

void small_sweep(const SmallBox* boxes, const std::uint8_t* const order[3], std::uint32_t m, const SweepPrice& price,
                 float cost_out[4], float left_count_out[4]) {
    const float* base = reinterpret_cast<const float*>(boxes);
    const auto record = [&](int axis, std::uint32_t j) { return base + 8 * std::size_t(order[axis][j]); };
    __m256 right[kSmallSubtree][3];  // candidate c: the boxes of [c + 1, m)
    right_boxes(record, m, right);
    const __m128 every = _mm_castsi128_ps(_mm_set1_epi32(-1));
    PrefixSweep sweep(price);
    for (std::uint32_t c = 0; c + 1 < m; ++c) {
        const std::uint32_t n_left = (c + 1 + price.mask) & ~price.mask,
                            n_right = (m - c - 1 + price.mask) & ~price.mask;
        sweep.offer(
            record(0, c), record(1, c), record(2, c), right[c], _mm_set1_ps(float(n_left)), _mm_set1_ps(float(n_right)),
            [&] { return _mm_set1_ps(float(n_left + n_right)); }, float(c + 1), every);
    }
    sweep.store(cost_out, left_count_out);
}

}  // namespace bvhlab::avx2
