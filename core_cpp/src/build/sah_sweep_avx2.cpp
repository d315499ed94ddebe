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
/// operations of both in their order, lane a for axis a. kByArea: the price's inv_area > 0 (the
/// sweep asks once, not at each candidate).
template <bool kByArea>
class PrefixSweep {
public:
    explicit PrefixSweep(const SweepPrice& price)
        : trav_(_mm_set1_ps(price.traversal)),
          isect_(_mm_set1_ps(price.intersection)),
          inv_(_mm_set1_ps(price.inv_area)) {
        box_[0] = box_[1] = box_[2] = _mm256_set1_ps(kInf);
    }

    /// Grows the left boxes by the records x, y, z (one per axis) and offers the candidate whose
    /// right boxes are `right`, with the counts as SahCost::counted has them, as floats in every
    /// lane of [left | right] (`counts`), keyed `key` (in every lane), in the lanes of `allowed`.
    /// `total()`, the counts' sum as floats, is read only for a parent of zero area. kMasked:
    /// `allowed` may leave lanes out (else every lane is).
    template <bool kMasked = true, class Total>
    void offer(const float* x, const float* y, const float* z, const __m256 right[3], __m256 counts, const Total& total,
               __m128 key, __m128 allowed) {
        box_[0] = _mm256_min_ps(box_[0], _mm256_load_ps(x)), box_[1] = _mm256_min_ps(box_[1], _mm256_load_ps(y));
        box_[2] = _mm256_min_ps(box_[2], _mm256_load_ps(z));
        __m128 ratio;
        if constexpr (kByArea) {
            const __m256 zero = _mm256_setzero_ps(), sign = _mm256_set1_ps(-0.0f);
            const __m256 areas =
                half_areas(extents(box_[0], right[0], sign, zero), extents(box_[1], right[1], sign, zero),
                           extents(box_[2], right[2], sign, zero), zero);  // [left | right]
            const __m256 weighted = _mm256_mul_ps(areas, counts);
            ratio = _mm_mul_ps(_mm_add_ps(_mm256_castps256_ps128(weighted), _mm256_extractf128_ps(weighted, 1)), inv_);
        } else {
            (void)counts;
            ratio = total();
        }
        const __m128 cost = _mm_add_ps(trav_, _mm_mul_ps(ratio, isect_));
        __m128 taken = _mm_cmplt_ps(cost, best_);  // strictly cheaper: ties keep the first
        if constexpr (kMasked) taken = _mm_and_ps(taken, allowed);
        best_ = _mm_blendv_ps(best_, cost, taken), key_ = _mm_blendv_ps(key_, key, taken);
    }
    void store(float cost[4], float key[4]) const { _mm_storeu_ps(cost, best_), _mm_storeu_ps(key, key_); }

private:
    __m256 box_[3];
    const __m128 trav_, isect_, inv_;
    __m128 best_ = _mm_set1_ps(kInf), key_ = _mm_setzero_ps();
};

/// Calls sweep.operator()<kByArea>() with PrefixSweep's kByArea for `price`: decided once per node.
template <class Sweep>
void sweep_by_area(const SweepPrice& price, const Sweep& sweep) {
    if (price.inv_area > 0.0f) sweep.template operator()<true>();
    else sweep.template operator()<false>();
}

/// SahCost::counted(n) as a float, row[log2(block)][n] for the masks block - 1 of every block
/// (1..kMaxSahBlock, powers of two) and the counts of a small subtree's nodes.
struct CountedTable {
    static constexpr int kBlocks = __builtin_ctz(kMaxSahBlock) + 1;
    float row[kBlocks][kSmallSubtree + 1];
    constexpr CountedTable() : row() {
        for (int b = 0; b < kBlocks; ++b)
            for (std::uint32_t n = 0; n <= kSmallSubtree; ++n) {
                const std::uint32_t mask = (1u << b) - 1;
                row[b][n] = float((n + mask) & ~mask);
            }
    }
};
constexpr CountedTable kCounted;

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
    __m128i n_right = _mm_setzero_si128();
    for (std::uint32_t j = bins - 1; j > 0; --j)
        _mm_store_si128(reinterpret_cast<__m128i*>(right_n[j - 1]), n_right = _mm_add_epi32(n_right, counts(j)));
    // SahCost::counted under the parent, which holds every reference of each axis's buckets
    const __m128i mask = _mm_set1_epi32(int(price.mask)), keep = _mm_set1_epi32(int(~price.mask));
    const auto counted = [&](__m128i v) { return _mm_and_si128(_mm_add_epi32(v, mask), keep); };
    const __m128 zero = _mm_setzero_ps();
    const auto sweep = [&]<bool kByArea>() {
        PrefixSweep<kByArea> sweep(price);  // among candidates with both sides non-empty
        __m128i n = _mm_setzero_si128();
        for (std::uint32_t c = 0; c + 1 < bins; ++c) {
            n = _mm_add_epi32(n, counts(c));
            const __m128i left_n = counted(n),
                          right_c = counted(_mm_load_si128(reinterpret_cast<const __m128i*>(right_n[c])));
            const __m128 n_left = _mm_cvtepi32_ps(left_n), n_right = _mm_cvtepi32_ps(right_c);
            sweep.offer(
                record(0, c), record(1, c), record(2, c), right[c], _mm256_set_m128(n_right, n_left),
                [&] { return _mm_cvtepi32_ps(_mm_add_epi32(left_n, right_c)); }, _mm_set1_ps(float(c)),
                _mm_and_ps(_mm_cmplt_ps(zero, n_left), _mm_cmplt_ps(zero, n_right)));
        }
        sweep.store(cost_out, key_out);
    };
    sweep_by_area(price, sweep);
}

void small_ranks(const float* c2, std::uint32_t n, std::uint8_t (*order)[kSmallSubtree]) {
    // rank of i = #{j < i : c2[j] <= c2[i]} + #{j > i : c2[j] < c2[i]}, per axis lane. Counted
    // as integers (a true compare is -1, subtracted), two references i at a time, so that each
    // pair of others is loaded once for both and the two sums do not wait on each other.
    const auto two = [&](std::uint32_t j) { return _mm256_loadu_ps(c2 + 4 * std::size_t(j)); };  // j and j + 1
    const auto one = [&](std::uint32_t j) { return _mm_loadu_ps(c2 + 4 * std::size_t(j)); };
    const auto both = [](__m128 v) { return _mm256_set_m128(v, v); };
    const auto lanes = [](__m256i v) {  // the two halves' sums
        return _mm_add_epi32(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
    };
    const auto count = [](__m256 mask) { return _mm256_castps_si256(mask); };
    const auto put = [&](std::uint32_t i, __m128i rank) {
        alignas(16) std::uint32_t r[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(r), rank);
        for (int a = 0; a < 3; ++a) order[a][r[a]] = std::uint8_t(i);
    };
    std::uint32_t i = 0;
    for (; i + 2 <= n; i += 2) {
        const __m128 c0 = one(i), c1 = one(i + 1);
        const __m256 b0 = both(c0), b1 = both(c1);
        __m256i r0 = _mm256_setzero_si256(), r1 = r0;
        std::uint32_t j = 0;
        for (; j < i; j += 2) {  // i is even: whole pairs before it
            const __m256 v = two(j);
            r0 = _mm256_sub_epi32(r0, count(_mm256_cmp_ps(v, b0, _CMP_LE_OQ)));
            r1 = _mm256_sub_epi32(r1, count(_mm256_cmp_ps(v, b1, _CMP_LE_OQ)));
        }
        for (j = i + 2; j + 2 <= n; j += 2) {
            const __m256 v = two(j);
            r0 = _mm256_sub_epi32(r0, count(_mm256_cmp_ps(v, b0, _CMP_LT_OQ)));
            r1 = _mm256_sub_epi32(r1, count(_mm256_cmp_ps(v, b1, _CMP_LT_OQ)));
        }
        __m128i s0 = lanes(r0), s1 = lanes(r1);
        if (j < n) {
            const __m128 v = one(j);
            s0 = _mm_sub_epi32(s0, _mm_castps_si128(_mm_cmplt_ps(v, c0)));
            s1 = _mm_sub_epi32(s1, _mm_castps_si128(_mm_cmplt_ps(v, c1)));
        }
        // the two against each other: i + 1 comes after i, i before i + 1
        s0 = _mm_sub_epi32(s0, _mm_castps_si128(_mm_cmplt_ps(c1, c0)));
        s1 = _mm_sub_epi32(s1, _mm_castps_si128(_mm_cmple_ps(c0, c1)));
        put(i, s0), put(i + 1, s1);
    }
    if (i < n) {  // the last of an odd count: every other reference comes before it
        const __m128 c0 = one(i);
        const __m256 b0 = both(c0);
        __m256i r0 = _mm256_setzero_si256();
        std::uint32_t j = 0;
        for (; j + 2 <= i; j += 2) r0 = _mm256_sub_epi32(r0, count(_mm256_cmp_ps(two(j), b0, _CMP_LE_OQ)));
        put(i, lanes(r0));
    }
}

void small_sweep(const SmallBox* boxes, const std::uint8_t* const order[3], std::uint32_t m, const SweepPrice& price,
                 float cost_out[4], float left_count_out[4]) {
    const float* base = reinterpret_cast<const float*>(boxes);
    const auto record = [&](int axis, std::uint32_t j) { return base + 8 * std::size_t(order[axis][j]); };
    __m256 right[kSmallSubtree][3];  // candidate c: the boxes of [c + 1, m)
    right_boxes(record, m, right);
    // SahCost::counted of every count the node can have, as floats: the candidates look them up
    const float* const counted = kCounted.row[__builtin_popcount(price.mask)];
    const auto sweep = [&]<bool kByArea>() {
        PrefixSweep<kByArea> sweep(price);
        __m128 key = _mm_set1_ps(1.0f);  // the left count, c + 1
        for (std::uint32_t c = 0; c + 1 < m; ++c, key = _mm_add_ps(key, _mm_set1_ps(1.0f))) {
            const __m128 n_left = _mm_broadcast_ss(counted + c + 1), n_right = _mm_broadcast_ss(counted + m - c - 1);
            sweep.template offer<false>(
                record(0, c), record(1, c), record(2, c), right[c], _mm256_set_m128(n_right, n_left),
                [&] { return _mm_add_ps(n_left, n_right); }, key, _mm_setzero_ps());
        }
        sweep.store(cost_out, left_count_out);
    };
    sweep_by_area(price, sweep);
}

}  // namespace bvhlab::avx2
