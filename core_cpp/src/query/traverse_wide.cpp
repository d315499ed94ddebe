// Closest-hit traversal of the 8-wide tree: the portable path (SSE on x86-64, plain C++
// elsewhere), the dispatch to the AVX2 path (isa.h), and the helpers both call.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>

#include "bvhlab/isa.h"
#include "bvhlab/simd.h"
#include "bvhlab/traverse.h"
#include "wide_kernel.h"
#include "wide_kernels.h"
#ifdef __SSSE3__
#include <tmmintrin.h>
#endif

namespace bvhlab {

#ifndef BVHLAB_RECORDED_WIDE_WALK  // (traverse_wide_record.cpp: this file again, the recorded walk alone)
bool hit_packet_sphere(const PrimPacket& k, int lane, const Ray& ray, Hit& hit) {
    const gpu::vec3 centre{k.v[0][0][lane], k.v[0][1][lane], k.v[0][2][lane]};
    const PackedPrim p{centre, 0, {k.v[1][0][lane], 0, 0}, k.ref[lane], {}, 0};
    return hit_sphere(p, RayQuery(ray), hit);
}
#endif

namespace portable {

#ifdef BVHLAB_SSE
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
#ifdef __SSSE3__
/// By a byte shuffle: lane i takes bytes 4·index .. 4·index + 3 (4·index spread over the lane's
/// four bytes by a first shuffle, then 0, 1, 2, 3 added; no carries: 4·3 + 3 < 256).
inline L4 permute(L4 x, const std::int32_t* lanes) {
    const __m128i first = _mm_slli_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(lanes)), 2);
    const __m128i spread = _mm_shuffle_epi8(first, _mm_setr_epi8(0, 0, 0, 0, 4, 4, 4, 4, 8, 8, 8, 8, 12, 12, 12, 12));
    const __m128i bytes = _mm_add_epi8(spread, _mm_set1_epi32(0x03020100));
    return {_mm_castsi128_ps(_mm_shuffle_epi8(_mm_castps_si128(x.v), bytes))};
}
#else
inline L4 permute(L4 x, const std::int32_t* lanes) {
    alignas(16) float f[4];
    x.store(f);
    return {_mm_setr_ps(f[lanes[0]], f[lanes[1]], f[lanes[2]], f[3])};
}
#endif
inline L4 operator+(L4 a, L4 b) { return {_mm_add_ps(a.v, b.v)}; }
inline L4 operator-(L4 a, L4 b) { return {_mm_sub_ps(a.v, b.v)}; }
inline L4 operator*(L4 a, L4 b) { return {_mm_mul_ps(a.v, b.v)}; }
inline L4 operator/(L4 a, L4 b) { return {_mm_div_ps(a.v, b.v)}; }
inline M4 operator!=(L4 a, L4 b) { return {_mm_cmpneq_ps(a.v, b.v)}; }
inline M4 operator>=(L4 a, L4 b) { return {_mm_cmpge_ps(a.v, b.v)}; }
inline M4 operator<=(L4 a, L4 b) { return {_mm_cmple_ps(a.v, b.v)}; }
inline M4 operator>(L4 a, L4 b) { return {_mm_cmpgt_ps(a.v, b.v)}; }
inline L4 raise(L4 acc, L4 t) { return {_mm_max_ps(t.v, acc.v)}; }  // t > acc ? t : acc
inline L4 lower(L4 acc, L4 t) { return {_mm_min_ps(t.v, acc.v)}; }  // t < acc ? t : acc
inline int le_bits(L4 a, L4 b) { return _mm_movemask_ps(_mm_cmple_ps(a.v, b.v)); }
#else
struct M4 {
    bool m[4];
};
inline M4 operator&(M4 a, M4 b) { return {{a.m[0] && b.m[0], a.m[1] && b.m[1], a.m[2] && b.m[2], a.m[3] && b.m[3]}}; }
inline M4 operator|(M4 a, M4 b) { return {{a.m[0] || b.m[0], a.m[1] || b.m[1], a.m[2] || b.m[2], a.m[3] || b.m[3]}}; }
inline int bits(M4 a) { return int(a.m[0]) | int(a.m[1]) << 1 | int(a.m[2]) << 2 | int(a.m[3]) << 3; }
struct L4 {
    float v[4];
    static L4 load(const float* p) { return {{p[0], p[1], p[2], p[3]}}; }
    static L4 splat(float s) { return {{s, s, s, s}}; }
    static L4 set(float a, float b, float c, float d) { return {{a, b, c, d}}; }
    void store(float* p) const {
        for (int i = 0; i < 4; ++i) p[i] = v[i];
    }
};
inline L4 permute(L4 x, const std::int32_t* lanes) { return {{x.v[lanes[0]], x.v[lanes[1]], x.v[lanes[2]], x.v[3]}}; }
inline int sign_bits(L4 x) {
    return int(std::signbit(x.v[0])) | int(std::signbit(x.v[1])) << 1 | int(std::signbit(x.v[2])) << 2 |
           int(std::signbit(x.v[3])) << 3;
}
/// Lane by lane: op(a[i], b[i]) for the four lanes (floats for arithmetic, bools for comparisons).
template <class R, class Op>
inline R lanes(L4 a, L4 b, Op op) {
    return {{op(a.v[0], b.v[0]), op(a.v[1], b.v[1]), op(a.v[2], b.v[2]), op(a.v[3], b.v[3])}};
}
inline L4 operator+(L4 a, L4 b) { return lanes<L4>(a, b, std::plus<>()); }
inline L4 operator-(L4 a, L4 b) { return lanes<L4>(a, b, std::minus<>()); }
inline L4 operator*(L4 a, L4 b) { return lanes<L4>(a, b, std::multiplies<>()); }
inline L4 operator/(L4 a, L4 b) { return lanes<L4>(a, b, std::divides<>()); }
inline M4 operator!=(L4 a, L4 b) { return lanes<M4>(a, b, std::not_equal_to<>()); }
inline M4 operator>=(L4 a, L4 b) { return lanes<M4>(a, b, std::greater_equal<>()); }
inline M4 operator<=(L4 a, L4 b) { return lanes<M4>(a, b, std::less_equal<>()); }
inline M4 operator>(L4 a, L4 b) { return lanes<M4>(a, b, std::greater<>()); }
inline L4 raise(L4 acc, L4 t) {
    for (int i = 0; i < 4; ++i) acc.v[i] = t.v[i] > acc.v[i] ? t.v[i] : acc.v[i];
    return acc;
}
inline L4 lower(L4 acc, L4 t) {
    for (int i = 0; i < 4; ++i) acc.v[i] = t.v[i] < acc.v[i] ? t.v[i] : acc.v[i];
    return acc;
}
inline int le_bits(L4 a, L4 b) { return bits(a <= b); }
#endif

/// Eight floats as two halves.
struct L8 {
    L4 a, b;
    static L8 load(const float* p) { return {L4::load(p), L4::load(p + 4)}; }
    static L8 splat(float s) { return {L4::splat(s), L4::splat(s)}; }
    void store(float* p) const { a.store(p), b.store(p + 4); }
    float lane(int k) const {
        alignas(32) float f[8];
        store(f);
        return f[k];
    }
};
inline L8 operator+(L8 x, L8 y) { return {x.a + y.a, x.b + y.b}; }
inline L8 operator-(L8 x, L8 y) { return {x.a - y.a, x.b - y.b}; }
inline L8 operator*(L8 x, L8 y) { return {x.a * y.a, x.b * y.b}; }
inline L8 raise(L8 acc, L8 t) { return {raise(acc.a, t.a), raise(acc.b, t.b)}; }
inline L8 lower(L8 acc, L8 t) { return {lower(acc.a, t.a), lower(acc.b, t.b)}; }
inline int le_bits(L8 x, L8 y) { return le_bits(x.a, y.a) | le_bits(x.b, y.b) << 4; }

/// The key the wide traversal sorts an entered child slot `lane` by (wide_traverse.inl
/// enter_children): an int ordered as `middle` (entry + exit) is, the float's bits with a
/// negative value's magnitude bits flipped, its last three bits replaced by the slot, so that
/// keys are distinct (ties, and middles within 8 ulps, go by slot). The AVX2 path computes the
/// same keys (traverse_wide_avx2.cpp push_children), so both visit the same nodes in the same
/// order.
inline std::int32_t child_key(float middle, int lane) {
    std::int32_t b;
    std::memcpy(&b, &middle, sizeof b);
    b ^= (b >> 31) & std::numeric_limits<std::int32_t>::max();
    return (b & ~7) | lane;
}

/// Writes the children of `node` in `mask` (the h slots the ray enters) but the nearest to
/// index[0, h - 1) and t[0, h - 1) (from t0, the entries), ordered by child_key
/// largest first (the farthest first); returns the nearest's slot. An insertion sort of the
/// entered slots only, two (the most common case) by one comparison without a loop.
inline int push_children(const WideNode& node, L8 t0, L8 t1, int mask, std::uint32_t* index, float* t) {
    alignas(32) float entry[8], exit[8];
    t0.store(entry), t1.store(exit);
    auto key_of = [&](int slot) { return child_key(entry[slot] + exit[slot], slot); };
    std::int32_t key[8];
    const int rest = mask & (mask - 1);
    key[0] = key_of(__builtin_ctz(unsigned(mask)));
    int h = 1;
    if (!(rest & (rest - 1))) {
        const std::int32_t k = key_of(__builtin_ctz(unsigned(rest)));
        key[h++] = k > key[0] ? key[0] : k;
        key[0] = k > key[0] ? k : key[0];
    } else {
        for (int m = rest; m; m &= m - 1) {
            const std::int32_t k = key_of(__builtin_ctz(unsigned(m)));
            int j = h++;
            for (; j > 0 && key[j - 1] < k; --j) key[j] = key[j - 1];
            key[j] = k;
        }
    }
    for (int j = 0; j + 1 < h; ++j) {  // the nearest, at h - 1, goes to cur, not the stack
        const int lane = key[j] & 7;
        index[j] = node.child[lane], t[j] = entry[lane];
    }
    return key[h - 1] & 7;
}

/// The slot in `mask` (two or more slots the ray enters) of the largest child_key: the child whose
/// span's middle lies farthest along the ray, as push_children would order it.
inline int farthest_slot(L8 t0, L8 t1, int mask) {
    alignas(32) float entry[8], exit[8];
    t0.store(entry), t1.store(exit);
    std::int32_t best = std::numeric_limits<std::int32_t>::min();
    for (int m = mask; m; m &= m - 1) {
        const int slot = __builtin_ctz(unsigned(m));
        const std::int32_t k = child_key(entry[slot] + exit[slot], slot);
        best = k > best ? k : best;
    }
    return best & 7;
}

/// The children of `node` in `mask` to index[0, popcount(mask)), in slot order.
inline void push_entered(const WideNode& node, int mask, std::uint32_t* index) {
    for (; mask; mask &= mask - 1) *index++ = node.child[__builtin_ctz(unsigned(mask))];
}

/// Bit k set where slot k of `node` is a leaf (kLeafChild).
inline int leaf_bits(const WideNode& node) {
#ifdef BVHLAB_SSE
    const auto* f = reinterpret_cast<const float*>(node.child);
    return _mm_movemask_ps(_mm_load_ps(f)) | _mm_movemask_ps(_mm_load_ps(f + 4)) << 4;
#else
    int bits = 0;
    for (int k = 0; k < 8; ++k) bits |= int(node.child[k] >> 31) << k;
    return bits;
#endif
}

#include "wide_traverse.inl"

}  // namespace portable

#ifndef BVHLAB_RECORDED_WIDE_WALK
Hit intersect_wide(const WideBvh& wide, const Bvh& bvh, const Ray& ray, std::uint32_t* nodes_visited) {
    const WideView view = view_of(wide);
    Hit hit = with_wide_kernels([&](auto k) { return decltype(k)::closest(view, ray, nodes_visited); });
    finish_wide_hit(bvh, ray, hit);
    return hit;
}

void order_by_octant(const std::uint8_t* octant, std::uint32_t count, std::uint32_t* order, std::uint32_t start[9]) {
    std::uint32_t at[8] = {};
    for (std::uint32_t i = 0; i < count; ++i) ++at[octant[i]];
    start[0] = 0;
    bool one = false;  // all of one octant (a camera's rays, most pieces): the order is the input's
    for (int k = 0; k < 8; ++k) one |= at[k] == count, start[k + 1] = start[k] + at[k], at[k] = start[k];
    if (one) {
        for (std::uint32_t i = 0; i < count; ++i) order[i] = i;
        return;
    }
    for (std::uint32_t i = 0; i < count; ++i) order[at[octant[i]]++] = i;
}

void group_by_octant(const Ray* rays, std::uint32_t count, std::uint32_t* order, std::uint32_t start[9]) {
    std::uint8_t octant[kWideBatch];  // count ≤ kWideBatch (intersect_wide_batch's pieces)
    for (std::uint32_t i = 0; i < count; ++i) octant[i] = std::uint8_t(octant_of(&rays[i].dir.x));
    order_by_octant(octant, count, order, start);
}

void intersect_wide_grouped(const WideBvh& wide, const Ray* rays, const std::uint32_t* order,
                            const std::uint32_t* start, Hit* hits, std::uint32_t* nodes_visited, WideWalk walk) {
    const WideView view = view_of(wide);
    if (walk == WideWalk::Interleaved) detail::interleaved_pieces.fetch_add(1, std::memory_order_relaxed);
    with_wide_kernels([&](auto k) { decltype(k)::closest_batch(view, rays, order, start, hits, nodes_visited, walk); });
}

void occluded_wide_grouped(const WideBvh& wide, const Ray* rays, const std::uint32_t* order, const std::uint32_t* start,
                           bool* occluded) {
    const WideView view = view_of(wide);
    with_wide_kernels([&](auto k) { decltype(k)::any_batch(view, rays, order, start, occluded); });
}

void intersect_wide_batch(const WideBvh& wide, const Bvh& bvh, const Ray* rays, std::size_t count, Hit* hits,
                          std::uint32_t* nodes_visited, WideWalk walk) {
    std::uint32_t order[kWideBatch], start[9];
    for (std::size_t begin = 0; begin < count; begin += kWideBatch) {
        const auto n = std::uint32_t(std::min<std::size_t>(kWideBatch, count - begin));
        group_by_octant(rays + begin, n, order, start);
        intersect_wide_grouped(wide, rays + begin, order, start, hits + begin,
                               nodes_visited ? nodes_visited + begin : nullptr, walk);
        for (std::uint32_t i = 0; i < n; ++i) finish_wide_hit(bvh, rays[begin + i], hits[begin + i]);
    }
}

void occluded_wide_batch(const WideBvh& wide, const Ray* rays, std::size_t count, bool* occluded) {
    std::uint32_t order[kWideBatch], start[9];
    for (std::size_t begin = 0; begin < count; begin += kWideBatch) {
        const auto n = std::uint32_t(std::min<std::size_t>(kWideBatch, count - begin));
        group_by_octant(rays + begin, n, order, start);
        occluded_wide_grouped(wide, rays + begin, order, start, occluded + begin);
    }
}

bool occluded_wide(const WideBvh& wide, const Ray& ray) {
    const WideView view = view_of(wide);
    return with_wide_kernels([&](auto k) { return decltype(k)::any(view, ray); });
}

void start_tlas_walk(const Ray& ray, TlasWalk& walk) {
    with_wide_kernels([&](auto k) { decltype(k)::start_tlas(ray, walk); });
}

std::uint32_t next_tlas_leaf(const WideBvh& wide, TlasWalk& walk, float hit_t, WideRecorder* record) {
    const WideView view = view_of(wide);
    return with_wide_kernels([&](auto k) { return decltype(k)::next_tlas(view, walk, hit_t, record); });
}

#endif

}  // namespace bvhlab
