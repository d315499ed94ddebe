// The 8-wide traversal for CPUs with AVX2 (compiled with -mavx2, chosen at run time, isa.h):
// one 256-bit slab test checks a node's eight children. wide_traverse.inl has the algorithm; this
// file only gives it its vector types. See binning_avx2.cpp for why nothing here may call an
// inline function of another header.
#include <immintrin.h>

#include <cmath>

#include "wide_kernel.h"

namespace bvhlab::avx2 {

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
inline L4 permute(L4 x, int a, int b, int c) { return {_mm_permutevar_ps(x.v, _mm_setr_epi32(a, b, c, 3))}; }
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
inline L8 raise(L8 acc, L8 t) { return {_mm256_max_ps(t.v, acc.v)}; }  // t > acc ? t : acc
inline L8 lower(L8 acc, L8 t) { return {_mm256_min_ps(t.v, acc.v)}; }  // t < acc ? t : acc
inline int le_bits(L8 a, L8 b) { return _mm256_movemask_ps(_mm256_cmp_ps(a.v, b.v, _CMP_LE_OS)); }

#include "wide_traverse.inl"

}  // namespace bvhlab::avx2
