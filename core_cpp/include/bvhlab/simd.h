// simd.h — a 4-wide float vector for the hot loops of the builders (binning, partitioning).
// SSE where the compiler offers it (every x86-64), plain scalar code elsewhere (e.g. arm64 Macs).
#pragma once
#include <algorithm>
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
    void store(float* p) const { _mm_storeu_ps(p, v); }
    float lane(int i) const { alignas(16) float t[4]; _mm_store_ps(t, v); return t[i]; }
};
inline F4 operator+(F4 a, F4 b) { return {_mm_add_ps(a.v, b.v)}; }
inline F4 operator-(F4 a, F4 b) { return {_mm_sub_ps(a.v, b.v)}; }
inline F4 operator*(F4 a, F4 b) { return {_mm_mul_ps(a.v, b.v)}; }
inline F4 min(F4 a, F4 b) { return {_mm_min_ps(a.v, b.v)}; }
inline F4 max(F4 a, F4 b) { return {_mm_max_ps(a.v, b.v)}; }
/// Half the surface area of the box [lo, hi] (lanes 0-2); 0 for an empty box.
inline float half_area(F4 lo, F4 hi) {
    __m128 e = _mm_max_ps(_mm_sub_ps(hi.v, lo.v), _mm_setzero_ps());
    __m128 p = _mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1)));  // x·y, y·z, z·x
    return _mm_cvtss_f32(_mm_add_ss(_mm_add_ss(p, _mm_shuffle_ps(p, p, 1)), _mm_movehl_ps(p, p)));
}
#else
struct F4 {
    float v[4];
    static F4 load(const float* p) { return {{p[0], p[1], p[2], p[3]}}; }
    static F4 load3(const float* p) { return {{p[0], p[1], p[2], 0.0f}}; }
    static F4 splat(float s) { return {{s, s, s, s}}; }
    void store(float* p) const { std::copy(v, v + 4, p); }
    float lane(int i) const { return v[i]; }
};
#define BVHLAB_F4_OP(name, expr)                                          \
    inline F4 name(F4 a, F4 b) {                                          \
        F4 r;                                                             \
        for (int i = 0; i < 4; ++i) { float x = a.v[i], y = b.v[i]; r.v[i] = (expr); } \
        return r;                                                         \
    }
BVHLAB_F4_OP(operator+, x + y)
BVHLAB_F4_OP(operator-, x - y)
BVHLAB_F4_OP(operator*, x * y)
BVHLAB_F4_OP(min, std::min(x, y))
BVHLAB_F4_OP(max, std::max(x, y))
#undef BVHLAB_F4_OP
inline float half_area(F4 lo, F4 hi) {
    float e[3];
    for (int i = 0; i < 3; ++i) e[i] = std::max(hi.v[i] - lo.v[i], 0.0f);
    return e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
}
#endif

}  // namespace bvhlab
