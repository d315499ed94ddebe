// binning_avx2.cpp — the passes of binning.h for CPUs with AVX2 (compiled with -mavx2, chosen at
// run time, see isa.h). One 256-bit `min` grows a bucket's (lo, -hi) box. The arithmetic is that
// of the portable passes, operation for operation, so the buckets, and so the trees, are the same.
//
// This file must not call inline functions of the other headers (F4's operators, PrimRef's
// members...): the linker keeps one copy of each inline function, and an AVX2 copy would then
// run on CPUs without AVX2. It reads their data and uses only the helpers below.
#include <immintrin.h>

#include <type_traits>

#include "binning.h"

namespace bvhlab::avx2 {
namespace {

struct Kernel {
    const __m256 xyz = _mm256_castsi256_ps(_mm256_setr_epi32(-1, -1, -1, 0, -1, -1, -1, 0));
    // (lo, -hi) from (lo, hi) with lanes 3 and 7 zero; lane 3 becomes +inf, which keeps the count (Bucket)
    const __m256 flip_hi = _mm256_setr_ps(0, 0, 0, __builtin_inff(), -0.0f, -0.0f, -0.0f, -0.0f);
    const __m256i count_one = _mm256_setr_epi32(0, 0, 0, 1, 0, 0, 0, 0);
    const __m128 zero = _mm_setzero_ps(), sign = _mm_set1_ps(-0.0f);
};

/// Bucket coordinate clamped to [0, top]: (c2 - origin2) · scale, max with 0 first (NaN → 0).
inline __m128 bucket_coordinate(__m128 c2, __m128 origin2, __m128 scale, __m128 top, __m128 zero) {
    return _mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(c2, origin2), scale), zero), top);
}

/// Lane L of a vector of byte offsets, zero-extended (a 32-bit move; no sign extension).
template <int kLane>
using Lane = std::integral_constant<int, kLane>;
template <int kLane>
std::size_t offset(__m128i v, Lane<kLane>) {
    return std::uint32_t(_mm_extract_epi32(v, kLane));
}

/// Where axis a's buckets lie in a copy of B buckets per axis (lane a: a · 32 B bytes), so that
/// one shift and one add give a reference's three bucket offsets (binning.h Bucket: 32 bytes).
struct AxisOffsets {
    __m128i bucket;
    explicit AxisOffsets(std::uint32_t bins) : bucket(_mm_setr_epi32(0, 32 * int(bins), 64 * int(bins), 0)) {}
};

/// Adds a reference, (lo, -hi) box with +inf in lane 3 and bucket indices k on the three axes,
/// to one copy of buckets starting at `base`: one min grows the box and keeps the count in lane
/// 3, one integer add counts the reference (Bucket).
inline void add_to_buckets(char* base, const AxisOffsets& axes, __m128i k, __m256 box_of_ref, __m256i count_one) {
    const __m128i at = _mm_add_epi32(_mm_slli_epi32(k, 5), axes.bucket);
    const std::uint64_t low = std::uint64_t(_mm_cvtsi128_si64(at));  // lanes 0 and 1 in one move
    char* b[3] = {base + std::uint32_t(low), base + (low >> 32), base + offset(at, Lane<2>())};
    for (char* p : b) {
        float* box = reinterpret_cast<float*>(p);
        const __m256 grown = _mm256_min_ps(_mm256_load_ps(box), box_of_ref);
        _mm256_store_ps(box, _mm256_castsi256_ps(_mm256_add_epi32(_mm256_castps_si256(grown), count_one)));
    }
}

}  // namespace

void reset_buckets(Bucket* bucket, std::size_t n, const Bucket& empty) {
    const __m256 e = _mm256_load_ps(reinterpret_cast<const float*>(&empty));
    for (std::size_t i = 0; i < n; ++i) _mm256_store_ps(reinterpret_cast<float*>(bucket + i), e);
}

void merge_buckets(Bucket* into, const Bucket* other, std::size_t n) {
    // BinSet::merge: the union of the boxes by one min, the counts' sum (the biased bits of both,
    // less one bias) put into lane 3
    const __m256i bias = _mm256_setr_epi32(0, 0, 0, int(Bucket::kCountBias), 0, 0, 0, 0);
    for (std::size_t i = 0; i < n; ++i) {
        float* b = reinterpret_cast<float*>(into + i);
        const __m256 x = _mm256_load_ps(b), y = _mm256_load_ps(reinterpret_cast<const float*>(other + i));
        const __m256i sum = _mm256_sub_epi32(_mm256_add_epi32(_mm256_castps_si256(x), _mm256_castps_si256(y)), bias);
        _mm256_store_ps(b, _mm256_blend_ps(_mm256_min_ps(x, y), _mm256_castsi256_ps(sum), 0x08));
    }
}

void bin_refs(const PrimRef* refs, Range r, const BinFrame& f, const BinSet copies[2]) {
    const Kernel c;
    const AxisOffsets axes(f.bins);
    char* const base[2] = {reinterpret_cast<char*>(copies[0].bucket), reinterpret_cast<char*>(copies[1].bucket)};
    const __m128 origin2 = f.origin2.v, scale = f.scale.v, top = f.top.v;
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        const __m256 v = _mm256_and_ps(_mm256_loadu_ps(reinterpret_cast<const float*>(refs + i)), c.xyz);
        const __m128 c2 = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
        const __m128i k = _mm_cvttps_epi32(bucket_coordinate(c2, origin2, scale, top, c.zero));
        add_to_buckets(base[i & 1], axes, k, _mm256_xor_ps(v, c.flip_hi), c.count_one);
    }
}

namespace {

/// Where the pass writes next, as addresses: the next left slot, one past the next right slot.
struct Cursors {
    std::uintptr_t left, right;
};

/// The fused pass over one range: its constants, set up once, and the step for one reference.
/// The children's data are indexed by l, 1 for a reference going left and 0 for one going right.
template <bool kCentroids>
class FusedPass {
public:
    FusedPass(const BinFrame& parent, const BinSplit& split, const ChildBinning child[2])
        : to_side_(5u - std::uint32_t(split.axis)),
          axes_(parent.bins),
          top_(parent.top.v),
          split_at_(split_threshold(parent, split).v) {
        for (int s = 0; s < 2; ++s) {
            const int l = 1 - s;
            side_[l].origin2 = child[s].frame.origin2.v, side_[l].scale = child[s].frame.scale.v;
            for (int k = 0; k < 2; ++k)
                bucket_[l][k] = child[s].copies ? reinterpret_cast<char*>(child[s].copies[k].bucket) : nullptr;
        }
        for (auto& copy : acc_)
            for (auto& a : copy) _mm256_store_ps(a, _mm256_set1_ps(__builtin_inff()));
    }

    /// Reference `raw`: to its side's next slot, `at` (left fills forward, right backward; the
    /// slot is selected, not branched to: at the top of the tree the side is a coin toss), then
    /// into its child's copy kCopy of the buckets. One store of the reference, at its slot: the
    /// pass stores three buckets a reference too, and storing it at both cursors as scatter()'s
    /// uncontained mode does (partition.h) made the one-thread Sponza build 1-2% slower.
    template <int kCopy>
    void step(__m256 raw, Cursors& at) {
        const __m256 v = _mm256_and_ps(raw, c_.xyz);
        const __m128 c2 = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
        // 32 (a slot, and one side's stride below) when c2 is below the split's threshold on its
        // axis (split_threshold(): the other lanes never are), else 0.
        const std::uintptr_t lb = std::uint32_t(_mm_movemask_ps(_mm_cmplt_ps(c2, split_at_))) << to_side_;
        _mm256_storeu_ps(reinterpret_cast<float*>(lb ? at.left : at.right - 32), raw);
        at.left += lb;
        at.right += lb - 32;
        const std::uint32_t l = std::uint32_t(lb >> 5);
        if constexpr (kCentroids) {
            float* a = acc_[kCopy][l];
            const __m256 cc = _mm256_insertf128_ps(_mm256_castps128_ps256(c2), _mm_xor_ps(c2, c_.sign), 1);
            _mm256_store_ps(a, _mm256_min_ps(_mm256_load_ps(a), cc));
        }
        const char* side = reinterpret_cast<const char*>(side_) + lb;
        if (char* base = *reinterpret_cast<char* const*>(reinterpret_cast<const char*>(bucket_) + lb + 8 * kCopy)) {
            const __m128 origin2 = _mm_load_ps(reinterpret_cast<const float*>(side)),
                         scale = _mm_load_ps(reinterpret_cast<const float*>(side + 16));
            // The child's box holds the reference's, so c2 - origin2 >= 0: only the top needs a clamp.
            const __m128 x = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(c2, origin2), scale), top_);
            add_to_buckets(base, axes_, _mm_cvttps_epi32(x), _mm256_xor_ps(v, c_.flip_hi), c_.count_one);
        }
    }

    /// Each side's twice-centroid bounds merged into sides.
    void finish(CentroidBounds sides[2]) const {
        for (int s = 0; s < 2 && kCentroids; ++s) {
            const int l = 1 - s;
            const __m256 both = _mm256_min_ps(_mm256_load_ps(acc_[0][l]), _mm256_load_ps(acc_[1][l]));
            sides[s].lo.v = _mm_min_ps(sides[s].lo.v, _mm256_castps256_ps128(both));
            sides[s].neg_hi.v = _mm_min_ps(sides[s].neg_hi.v, _mm256_extractf128_ps(both, 1));
        }
    }

private:
    const Kernel c_;
    const std::uint32_t to_side_;  ///< shifts the split axis's bit of a compare mask to 32
    const AxisOffsets axes_;
    const __m128 top_;
    const __m128 split_at_;
    /// [l]: each child's frame, 32 bytes apart, so that a reference's 0 or 32 picks its side's.
    struct alignas(32) Side {
        __m128 origin2, scale;
    } side_[2];
    /// [l][copy]: where the child's buckets start (null: not binned), 32 bytes a side.
    alignas(32) char* bucket_[2][4] = {};
    // Twice-centroid (lo, -hi) per [copy][l]: even and odd references alternate, so that a run
    // going one way does not chain through one min.
    alignas(32) float acc_[2][2][8];
};

template <bool kCentroids>
std::uint32_t partition_and_bin_impl(const PrimRef* __restrict src, PrimRef* __restrict dst, Range r,
                                     std::uint32_t left, std::uint32_t right, const BinFrame& parent,
                                     const BinSplit& split, const ChildBinning child[2], CentroidBounds sides[2]) {
    FusedPass<kCentroids> pass(parent, split, child);
    // Locals, not members of the pass: its frames are read through pointers that could alias them.
    Cursors at{reinterpret_cast<std::uintptr_t>(dst + left), reinterpret_cast<std::uintptr_t>(dst + right)};
    auto load = [](const PrimRef* p) { return _mm256_loadu_ps(reinterpret_cast<const float*>(p)); };
    // Reference i uses copy i & 1 of the buckets (consecutive references do not wait on each
    // other's stores); the loop runs in pairs so that the copy is a constant.
    const PrimRef *p = src + r.begin, *const end = src + r.end;
    if (p < end && (r.begin & 1)) pass.template step<1>(load(p++), at);
    for (; end - p >= 2; p += 2) pass.template step<0>(load(p), at), pass.template step<1>(load(p + 1), at);
    if (p < end) pass.template step<0>(load(p), at);
    pass.finish(sides);
    return std::uint32_t(reinterpret_cast<const PrimRef*>(at.left) - dst);
}

}  // namespace

std::uint32_t partition_and_bin(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                                const BinFrame& parent, const BinSplit& split, const ChildBinning child[2],
                                CentroidBounds sides[2]) {
    return sides ? partition_and_bin_impl<true>(src, dst, r, left, right, parent, split, child, sides)
                 : partition_and_bin_impl<false>(src, dst, r, left, right, parent, split, child, sides);
}

}  // namespace bvhlab::avx2
