// The 8-wide traversal for CPUs with AVX2 (compiled with -mavx2, chosen at run time, isa.h):
// one 256-bit slab test checks a node's eight children. wide_traverse.inl has the algorithm; this
// file only gives it its vector types. See binning_avx2.cpp for why nothing here may call an
// inline function of another header.
#include <immintrin.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>

#include "transpose_avx2.h"
#include "wide_kernel.h"

// avx2, or avx512 where a *_avx512.cpp file includes this one (isa.h)
#ifndef BVHLAB_KERNEL_NS
#define BVHLAB_KERNEL_NS avx2
#endif
namespace bvhlab::BVHLAB_KERNEL_NS {

struct M4 {
    __m128 m;
};
inline M4 operator&(M4 a, M4 b) { return {_mm_and_ps(a.m, b.m)}; }
inline M4 operator|(M4 a, M4 b) { return {_mm_or_ps(a.m, b.m)}; }
inline int bits(M4 a) { return _mm_movemask_ps(a.m); }
struct L4 {
    __m128 v;
    static L4 load(const float* p) { return {_mm_loadu_ps(p)}; }
    static L4 splat(float s) { return {_mm_set1_ps(s)}; }
    static L4 set(float a, float b, float c, float d) { return {_mm_setr_ps(a, b, c, d)}; }
    void store(float* p) const { _mm_storeu_ps(p, v); }
};
inline int sign_bits(L4 x) { return _mm_movemask_ps(x.v); }
/// lanes[3] is 3 wherever it is called (wide_traverse.inl AxisOrder)
inline L4 permute(L4 x, const std::int32_t* lanes) {
    return {_mm_permutevar_ps(x.v, _mm_load_si128(reinterpret_cast<const __m128i*>(lanes)))};
}
inline L4 operator+(L4 a, L4 b) { return {_mm_add_ps(a.v, b.v)}; }
inline L4 operator-(L4 a, L4 b) { return {_mm_sub_ps(a.v, b.v)}; }
inline L4 operator*(L4 a, L4 b) { return {_mm_mul_ps(a.v, b.v)}; }
inline L4 operator/(L4 a, L4 b) { return {_mm_div_ps(a.v, b.v)}; }
inline M4 operator!=(L4 a, L4 b) { return {_mm_cmp_ps(a.v, b.v, _CMP_NEQ_UQ)}; }
inline M4 operator>=(L4 a, L4 b) { return {_mm_cmp_ps(a.v, b.v, _CMP_GE_OS)}; }
inline M4 operator<=(L4 a, L4 b) { return {_mm_cmp_ps(a.v, b.v, _CMP_LE_OS)}; }
inline M4 operator>(L4 a, L4 b) { return {_mm_cmp_ps(a.v, b.v, _CMP_GT_OS)}; }
inline L4 raise(L4 acc, L4 t) { return {_mm_max_ps(t.v, acc.v)}; }  // t > acc ? t : acc
inline L4 lower(L4 acc, L4 t) { return {_mm_min_ps(t.v, acc.v)}; }  // t < acc ? t : acc

struct L8 {
    __m256 v;
    static L8 load(const float* p) { return {_mm256_loadu_ps(p)}; }
    static L8 splat(float s) { return {_mm256_set1_ps(s)}; }
    void store(float* p) const { _mm256_storeu_ps(p, v); }
    /// Lane k by a permute, not a store and a reload (which waits on the store).
    float lane(int k) const { return _mm256_cvtss_f32(_mm256_permutevar8x32_ps(v, _mm256_set1_epi32(k))); }
};
inline L8 operator+(L8 a, L8 b) { return {_mm256_add_ps(a.v, b.v)}; }
inline L8 operator-(L8 a, L8 b) { return {_mm256_sub_ps(a.v, b.v)}; }
inline L8 operator*(L8 a, L8 b) { return {_mm256_mul_ps(a.v, b.v)}; }
inline L8 operator/(L8 a, L8 b) { return {_mm256_div_ps(a.v, b.v)}; }  // the packet walk's 1/d (wide_packet.inl)
inline L8 raise(L8 acc, L8 t) { return {_mm256_max_ps(t.v, acc.v)}; }  // t > acc ? t : acc
inline L8 lower(L8 acc, L8 t) { return {_mm256_min_ps(t.v, acc.v)}; }  // t < acc ? t : acc
inline int le_bits(L8 a, L8 b) { return _mm256_movemask_ps(_mm256_cmp_ps(a.v, b.v, _CMP_LE_OS)); }

/// One layer of the sorting network: each lane meets lane `partner` of the same layer; the lanes
/// of kTakesMax keep the larger key.
/// (The AVX-512 build's min then masked max, two instructions for three, and the entered lanes
/// below from le_bits' mask rather than a second compare, were slower: design.md, "An AVX-512
/// path".)
template <int kTakesMax>
inline __m256i exchange(__m256i v, __m256i partner) {
    return _mm256_blend_epi32(_mm256_min_epi32(v, partner), _mm256_max_epi32(v, partner), kTakesMax);
}

/// `b` where `mask` has the lane's bit, else `other` (AVX-512: one masked blend; AVX2: the
/// lanes' bits tested by a shift, a compare and a byte blend).
inline __m256i select_lanes(int mask, __m256i b, __m256i other) {
#if defined(__AVX512VL__)
    return _mm256_mask_blend_epi32(__mmask8(mask), other, b);
#else
    const __m256i bit = _mm256_sllv_epi32(_mm256_set1_epi32(1), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    const __m256i in = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(mask), bit), bit);
    return _mm256_blendv_epi8(other, b, in);
#endif
}

/// push_children for two entered slots (the commonest case after one, which never gets here):
/// the two keys (b, child_key of every slot) compared as scalars, and the farther one's child
/// written by the same permutes as the sorting network writes it, so that the stack holds what
/// the network would have written (tinybvh 1.9 BVH8_CPU's BVH8_2VALIDNODES case).
inline int push_two(const WideNode& node, L8 t0, __m256i b, int mask, std::uint32_t* index, float* t) {
    const int low = __builtin_ctz(unsigned(mask)), high = 31 - __builtin_clz(unsigned(mask));
    const int key_low = _mm256_cvtsi256_si32(_mm256_permutevar8x32_epi32(b, _mm256_set1_epi32(low)));
    const int key_high = _mm256_cvtsi256_si32(_mm256_permutevar8x32_epi32(b, _mm256_set1_epi32(high)));
    const bool low_far = key_low > key_high;
    const int far = low_far ? low : high;
    const __m256i v = _mm256_set1_epi32(far);
    const auto load = [](const std::uint32_t* p) { return _mm256_load_si256(reinterpret_cast<const __m256i*>(p)); };
    const auto store = [](std::uint32_t* p, __m256i x) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), x); };
    store(index, _mm256_permutevar8x32_epi32(load(node.child), v));
    _mm256_storeu_ps(t, _mm256_permutevar8x32_ps(t0.v, v));
    return low_far ? high : low;
}

/// push_children (traverse_wide.cpp says what it writes) without branches: child_key for the
/// eight slots at once, INT_MIN + slot for a slot not entered (below every entered one's key),
/// sorted largest first by the 19-comparator, depth-6 network for eight inputs (Knuth, TAOCP
/// vol. 3, 5.3.4), and the children permuted into that order by two vpermd; the nearest's slot
/// from a minimum across lanes, which does not wait for the sort.
inline int push_children(const WideNode& node, L8 t0, L8 t1, int mask, std::uint32_t* index, float* t) {
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    // by shifts rather than masks: the walk's registers full, the compiler made each mask anew
    // at every node (three instructions each); (b >> 31) & INT_MAX is 0 or -1 shifted right by
    // one, b & ~7 the bits shifted right and back by three (Sponza instructions a ray: design.md)
    __m256i b = _mm256_castps_si256(_mm256_add_ps(t0.v, t1.v));
    b = _mm256_xor_si256(b, _mm256_srli_epi32(_mm256_srai_epi32(b, 31), 1));
    b = _mm256_or_si256(_mm256_slli_epi32(_mm256_srli_epi32(b, 3), 3), lane);
    const int rest = mask & (mask - 1);
    if (!(rest & (rest - 1))) return push_two(node, t0, b, mask, index, t);
    const __m256i entered = _mm256_castps_si256(_mm256_cmp_ps(t0.v, t1.v, _CMP_LE_OS));
    __m256i m = _mm256_blendv_epi8(_mm256_set1_epi32(INT_MAX), b, entered);
    m = _mm256_min_epi32(m, _mm256_shuffle_epi32(m, _MM_SHUFFLE(2, 3, 0, 1)));
    m = _mm256_min_epi32(m, _mm256_shuffle_epi32(m, _MM_SHUFFLE(1, 0, 3, 2)));
    m = _mm256_min_epi32(m, _mm256_permute2x128_si256(m, m, 1));
    __m256i v = _mm256_blendv_epi8(_mm256_add_epi32(_mm256_set1_epi32(INT_MIN), lane), b, entered);
    v = exchange<0b00110011>(v, _mm256_shuffle_epi32(v, _MM_SHUFFLE(1, 0, 3, 2)));      // (0,2) (1,3) (4,6) (5,7)
    v = exchange<0b00001111>(v, _mm256_permute2x128_si256(v, v, 1));                    // (0,4) (1,5) (2,6) (3,7)
    v = exchange<0b01010101>(v, _mm256_shuffle_epi32(v, _MM_SHUFFLE(2, 3, 0, 1)));      // (0,1) (2,3) (4,5) (6,7)
    v = exchange<0b00001100>(v, _mm256_permute4x64_epi64(v, _MM_SHUFFLE(3, 1, 2, 0)));  // (2,4) (3,5)
    v = exchange<0b00001010>(v,
                             _mm256_permutevar8x32_epi32(v, _mm256_setr_epi32(0, 4, 2, 6, 1, 5, 3, 7)));  // (1,4) (3,6)
    v = exchange<0b00101010>(
        v, _mm256_permutevar8x32_epi32(v, _mm256_setr_epi32(0, 2, 1, 4, 3, 6, 5, 7)));  // (1,2) (3,4) (5,6)
    // all eight written, the entered first: what follows them is overwritten by later pushes
    // (vpermd reads the last three bits of each index: the slot)
    const auto load = [](const std::uint32_t* p) { return _mm256_load_si256(reinterpret_cast<const __m256i*>(p)); };
    const auto store = [](std::uint32_t* p, __m256i x) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), x); };
    store(index, _mm256_permutevar8x32_epi32(load(node.child), v));
    _mm256_storeu_ps(t, _mm256_permutevar8x32_ps(t0.v, v));
    return _mm256_cvtsi256_si32(m) & 7;
}

/// farthest_slot (traverse_wide.cpp says what it returns) without a loop: child_key for the eight
/// slots as push_children makes them, INT_MIN for a slot not in `mask`, the largest across lanes.
inline int farthest_slot(L8 t0, L8 t1, int mask) {
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    __m256i b = _mm256_castps_si256(_mm256_add_ps(t0.v, t1.v));
    b = _mm256_xor_si256(b, _mm256_srli_epi32(_mm256_srai_epi32(b, 31), 1));
    b = _mm256_or_si256(_mm256_slli_epi32(_mm256_srli_epi32(b, 3), 3), lane);
    __m256i m = select_lanes(mask, b, _mm256_set1_epi32(INT_MIN));
    m = _mm256_max_epi32(m, _mm256_shuffle_epi32(m, _MM_SHUFFLE(2, 3, 0, 1)));
    m = _mm256_max_epi32(m, _mm256_shuffle_epi32(m, _MM_SHUFFLE(1, 0, 3, 2)));
    m = _mm256_max_epi32(m, _mm256_permute2x128_si256(m, m, 1));
    return _mm256_cvtsi256_si32(m) & 7;
}

/// For each mask of entered slots, those slots in ascending order, a byte each (the rest 0): the
/// permute push_entered does (tinybvh 1.9's idxLUT256, a byte a lane rather than a word: 2 KiB).
struct CompressTable {
    std::uint64_t lanes[256];
    constexpr CompressTable() : lanes{} {
        for (int mask = 0; mask < 256; ++mask) {
            int n = 0;
            for (int slot = 0; slot < 8; ++slot)
                if (mask >> slot & 1) lanes[mask] |= std::uint64_t(slot) << (8 * n++);
        }
    }
};
constexpr CompressTable kCompress;

/// push_entered (traverse_wide.cpp says what it writes) by one permute of the child words: all
/// eight written, the entered first.
inline void push_entered(const WideNode& node, int mask, std::uint32_t* index) {
#if defined(__AVX512VL__)
    // the AVX-512 build: vpcompressd into a register (its form that writes memory is microcoded
    // on Zen 4 and 5), the rest zero
    const __m256i children = _mm256_load_si256(reinterpret_cast<const __m256i*>(node.child));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(index), _mm256_maskz_compress_epi32(__mmask8(mask), children));
#else
    const __m256i order = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(static_cast<long long>(kCompress.lanes[mask])));
    const __m256i children = _mm256_load_si256(reinterpret_cast<const __m256i*>(node.child));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(index), _mm256_permutevar8x32_epi32(children, order));
#endif
}

/// Bit k set where slot k of `node` is a leaf: the child words' bit 31 (kLeafChild) is their
/// sign bit as floats.
inline int leaf_bits(const WideNode& node) {
    return _mm256_movemask_ps(_mm256_load_ps(reinterpret_cast<const float*>(node.child)));
}

// the batch's closest-hit walk takes coherent rays as packets of eight (wide_packet.inl)
#define BVHLAB_WIDE_PACKETS
#include "wide_traverse.inl"

}  // namespace bvhlab::BVHLAB_KERNEL_NS
