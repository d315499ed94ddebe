// sah_sweep_avx2.h — the AVX2 sweeps and sort of sah_sweep_avx2.cpp, and what the bucket sweep
// (sah_sweep.cpp) and the small-subtree builder (small_subtree.cpp) hand them: plain data, so
// that the AVX2 file calls no inline function of the other headers (see binning_avx2.cpp).
#pragma once
#include <cstdint>

#include "bvhlab/simd.h"
#include "bvhlab/split.h"

namespace bvhlab {

struct Bucket;  // binning.h

/// A reference's box as (lo, -hi) in 32 bytes, so that one 256-bit `min` grows a box by it.
struct alignas(32) SmallBox {
    F4 lo, neg_hi;
};

/// A node's SahCost and LaneSplitCost constants: counts rounded by `mask` (SahCost::counted),
/// ratios by area when inv_area > 0, else the counts' sum.
struct SweepPrice {
    float traversal, intersection, inv_area;
    std::uint32_t mask;
};

#if defined(BVHLAB_AVX2_KERNELS)
namespace avx2 {
/// SmallSet::rank_all: order[a] gets the references i < n sorted by twice-centroid c2[i] (four
/// floats each, lane a for axis a), ties in index order.
void small_ranks(const float* c2, std::uint32_t n, std::uint8_t (*order)[kSmallSubtree]);
/// SmallBuilder::cheapest's sweep of a node (positions [0, m) of each order, m >= 2), the same
/// operations in the same order: per axis lane, the cheapest candidate's cost and its left
/// count, the first of equal costs (+inf and 0 where none).
void small_sweep(const SmallBox* boxes, const std::uint8_t* const order[3], std::uint32_t m, const SweepPrice& price,
                 float cost[4], float left_count[4]);
/// cheapest_bin_cuts's sweep of `bins` buckets per axis (BinSet's layout), the same operations in
/// the same order: per axis lane, the cheapest boundary's cost and its last left bucket, among
/// boundaries with both sides non-empty (+inf and 0 where none).
void bucket_sweep(const Bucket* bucket, std::uint32_t bins, const SweepPrice& price, float cost[4], float last_left[4]);
}  // namespace avx2
#endif

}  // namespace bvhlab
