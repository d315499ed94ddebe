// simd.h — a 4-wide float vector for the builders' portable loops (bounds, sweeps, the small
// exact SAH). SSE where the compiler offers it (every x86-64), plain scalar code elsewhere (e.g.
// arm64): both give the same bits for every operation, so trees do not depend on the platform.
// (The AVX2 kernels, *_avx2.cpp, use intrinsics directly; see isa.h.)
#pragma once
#include <cstdint>
#include <cstring>

#include "bvhlab/aabb.h"
#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#define BVHLAB_SSE 1
#endif

namespace bvhlab {

#ifdef BVHLAB_SSE
/// Four floats; lane 3 is ignored wherever a Vec3 is meant.
struct F4 {
    __m128 v;
    static F4 load(const float* p) { return {_mm_loadu_ps(p)}; }
    /// Loads x, y, z and zeroes lane 3: a PrimRef keeps integer bits there, which as floats are
    /// denormals, and arithmetic on denormals is very slow on x86.
    static F4 load3(const float* p) {
        const __m128 mask = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
        return {_mm_and_ps(_mm_loadu_ps(p), mask)};
    }
    static F4 splat(float s) { return {_mm_set1_ps(s)}; }
    /// (x, y, z, 0) built in registers: through a float[4] on the stack, GCC merged the lanes
    /// with integer moves and read them back in one load that waited for those stores.
    static F4 set3(float x, float y, float z) { return {_mm_setr_ps(x, y, z, 0.0f)}; }
    /// Four counts (each below 2^31) as floats, rounded as a scalar conversion rounds them.
    static F4 from_counts(const std::uint32_t* p) {
        return {_mm_cvtepi32_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)))};
    }
    void store(float* p) const { _mm_storeu_ps(p, v); }
    float lane(int i) const {
        alignas(16) float t[4];
        _mm_store_ps(t, v);
        return t[i];
    }
};
inline F4 operator+(F4 a, F4 b) { return {_mm_add_ps(a.v, b.v)}; }
inline F4 operator-(F4 a, F4 b) { return {_mm_sub_ps(a.v, b.v)}; }
inline F4 operator*(F4 a, F4 b) { return {_mm_mul_ps(a.v, b.v)}; }
inline F4 operator/(F4 a, F4 b) { return {_mm_div_ps(a.v, b.v)}; }
/// min(a, b) = a < b ? a : b and max(a, b) = a > b ? a : b per lane (SSE's rule: with a NaN,
/// the second operand); the scalar version below follows the same rule.
inline F4 min(F4 a, F4 b) { return {_mm_min_ps(a.v, b.v)}; }
inline F4 max(F4 a, F4 b) { return {_mm_max_ps(a.v, b.v)}; }
/// Exact negation (the sign bit flipped, so -0 and +0 swap too).
inline F4 neg(F4 a) { return {_mm_xor_ps(a.v, _mm_set1_ps(-0.0f))}; }
/// Lanes where a < b hold all ones, the others zero; `&` keeps the bits both have.
inline F4 less(F4 a, F4 b) { return {_mm_cmplt_ps(a.v, b.v)}; }
inline F4 less_equal(F4 a, F4 b) { return {_mm_cmple_ps(a.v, b.v)}; }
inline F4 operator&(F4 a, F4 b) { return {_mm_and_ps(a.v, b.v)}; }
/// Per lane: a where the mask is set, else b (the mask's lanes all ones or all zeros).
inline F4 select(F4 mask, F4 a, F4 b) { return {_mm_or_ps(_mm_and_ps(mask.v, a.v), _mm_andnot_ps(mask.v, b.v))}; }
/// Bit i set when lane i of a mask is set.
inline int lane_bits(F4 mask) { return _mm_movemask_ps(mask.v); }
inline bool any_lane(F4 mask) { return lane_bits(mask) != 0; }
/// Truncates each lane to an integer; the lanes must hold values in [0, 2^31).
inline void truncate_to_u32(F4 a, std::uint32_t out[4]) {
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm_cvttps_epi32(a.v));
}
/// The x, y and z lanes of four vectors, one vector per axis (a 4×3 transpose).
inline void transpose3(F4 a, F4 b, F4 c, F4 d, F4& x, F4& y, F4& z) {
    const __m128 ab_lo = _mm_unpacklo_ps(a.v, b.v), cd_lo = _mm_unpacklo_ps(c.v, d.v);  // ax bx ay by | cx dx cy dy
    const __m128 ab_hi = _mm_unpackhi_ps(a.v, b.v), cd_hi = _mm_unpackhi_ps(c.v, d.v);  // az bz .. | cz dz ..
    x.v = _mm_movelh_ps(ab_lo, cd_lo), y.v = _mm_movehl_ps(cd_lo, ab_lo), z.v = _mm_movelh_ps(ab_hi, cd_hi);
}
/// Half the surface area of the box [lo, hi] (lanes 0-2); 0 for an empty box.
inline float half_area(F4 lo, F4 hi) {
    __m128 e = _mm_max_ps(_mm_sub_ps(hi.v, lo.v), _mm_setzero_ps());
    __m128 p = _mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1)));  // x·y, y·z, z·x
    return _mm_cvtss_f32(_mm_add_ss(_mm_add_ss(p, _mm_shuffle_ps(p, p, 1)), _mm_movehl_ps(p, p)));
}
#else
struct F4 {
    float v[4];
    /// A copy of the bytes (as _mm_loadu_ps, which may alias): rows read this way hold integer
    /// words too (a node's index and info, a record's material), and reading them as floats broke
    /// strict aliasing: GCC kept a node's old index over one stored since (refit_pass).
    static F4 load(const float* p) {
        F4 r;
        std::memcpy(r.v, p, sizeof(r.v));
        return r;
    }
    static F4 load3(const float* p) { return {{p[0], p[1], p[2], 0.0f}}; }
    static F4 splat(float s) { return {{s, s, s, s}}; }
    static F4 set3(float x, float y, float z) { return {{x, y, z, 0.0f}}; }
    static F4 from_counts(const std::uint32_t* p) {
        return {{float(std::int32_t(p[0])), float(std::int32_t(p[1])), float(std::int32_t(p[2])),
                 float(std::int32_t(p[3]))}};
    }
    void store(float* p) const { std::memcpy(p, v, sizeof(v)); }
    float lane(int i) const { return v[i]; }
};
#define BVHLAB_F4_OP(name, expr)          \
    inline F4 name(F4 a, F4 b) {          \
        F4 r;                             \
        for (int i = 0; i < 4; ++i) {     \
            float x = a.v[i], y = b.v[i]; \
            r.v[i] = (expr);              \
        }                                 \
        return r;                         \
    }
BVHLAB_F4_OP(operator+, x + y)
BVHLAB_F4_OP(operator-, x - y)
BVHLAB_F4_OP(operator*, x* y)
BVHLAB_F4_OP(operator/, x / y)
BVHLAB_F4_OP(min, x < y ? x : y)
BVHLAB_F4_OP(max, x > y ? x : y)
#undef BVHLAB_F4_OP
inline F4 neg(F4 a) { return {{-a.v[0], -a.v[1], -a.v[2], -a.v[3]}}; }
inline F4 less(F4 a, F4 b) {
    std::uint32_t m[4];
    for (int i = 0; i < 4; ++i) m[i] = a.v[i] < b.v[i] ? ~0u : 0u;
    F4 r;
    std::memcpy(r.v, m, sizeof(m));
    return r;
}
inline F4 less_equal(F4 a, F4 b) {
    std::uint32_t m[4];
    for (int i = 0; i < 4; ++i) m[i] = a.v[i] <= b.v[i] ? ~0u : 0u;
    F4 r;
    std::memcpy(r.v, m, sizeof(m));
    return r;
}
inline F4 operator&(F4 a, F4 b) {
    std::uint32_t x[4], y[4];
    std::memcpy(x, a.v, sizeof(x)), std::memcpy(y, b.v, sizeof(y));
    for (int i = 0; i < 4; ++i) x[i] &= y[i];
    F4 r;
    std::memcpy(r.v, x, sizeof(x));
    return r;
}
inline F4 select(F4 mask, F4 a, F4 b) {
    std::uint32_t m[4];
    std::memcpy(m, mask.v, sizeof(m));
    F4 r;
    for (int i = 0; i < 4; ++i) r.v[i] = m[i] ? a.v[i] : b.v[i];
    return r;
}
inline int lane_bits(F4 mask) {
    std::uint32_t m[4];
    std::memcpy(m, mask.v, sizeof(m));
    return int(m[0] >> 31) | int(m[1] >> 31) << 1 | int(m[2] >> 31) << 2 | int(m[3] >> 31) << 3;
}
inline bool any_lane(F4 mask) { return lane_bits(mask) != 0; }
inline void truncate_to_u32(F4 a, std::uint32_t out[4]) {
    for (int i = 0; i < 4; ++i) out[i] = static_cast<std::uint32_t>(a.v[i]);
}
inline void transpose3(F4 a, F4 b, F4 c, F4 d, F4& x, F4& y, F4& z) {
    x = {{a.v[0], b.v[0], c.v[0], d.v[0]}}, y = {{a.v[1], b.v[1], c.v[1], d.v[1]}},
    z = {{a.v[2], b.v[2], c.v[2], d.v[2]}};
}
inline float half_area(F4 lo, F4 hi) {
    float e[3];
    for (int i = 0; i < 3; ++i) {
        const float d = hi.v[i] - lo.v[i];
        e[i] = d > 0.0f ? d : 0.0f;
    }
    return e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
}
#endif

/// Half areas of four boxes at once, each bit-identical to half_area(lo, hi) of that box.
inline F4 half_areas(const F4 lo[4], const F4 hi[4]) {
    const F4 zero = F4::splat(0.0f);
    F4 x, y, z;
    transpose3(max(hi[0] - lo[0], zero), max(hi[1] - lo[1], zero), max(hi[2] - lo[2], zero), max(hi[3] - lo[3], zero),
               x, y, z);
    return (x * y + y * z) + z * x;
}

/// The box [lo, hi] of lanes 0-2 (lane 3 ignored): the one conversion from the builders' vectors.
inline Aabb to_aabb(F4 lo, F4 hi) {
    return {{lo.lane(0), lo.lane(1), lo.lane(2)}, {hi.lane(0), hi.lane(1), hi.lane(2)}};
}

}  // namespace bvhlab
