// The batch's vector passes for CPUs with AVX2 (compiled with -mavx2, chosen at run time, isa.h;
// ray_piece.cpp picks): over the caller's rays eight at a time (ray_batch.h prepare_piece: the
// same checks, scaling by powers of two and octants, so the piece holds the same bits as the
// scalar pass writes) and over a piece's hits eight at a time (write_hits). See binning_avx2.cpp
// for why nothing here may call an inline function of another header: this file uses intrinsics
// alone, and Ray's and Hit's layouts through static_asserts.
#include <immintrin.h>

#include <cstddef>
#include <cstdint>

#include "bvhlab/coordinate_range.h"  // its constants alone
#include "bvhlab/ray.h"
#include "gpu_types.h"
#include "transpose_avx2.h"

// avx2, or avx512 where a *_avx512.cpp file includes this one (isa.h)
#ifndef BVHLAB_KERNEL_NS
#define BVHLAB_KERNEL_NS avx2
#endif
namespace bvhlab::BVHLAB_KERNEL_NS {
namespace {

static_assert(sizeof(Ray) == 8 * sizeof(float) && offsetof(Ray, origin) == 0 && offsetof(Ray, dir) == 12 &&
                  offsetof(Ray, tmin) == 24 && offsetof(Ray, tmax) == 28,
              "a Ray is one 32-byte row: origin, direction, tmin, tmax");

/// Component k (0, 1, 2) of the eight triples in a, b, c (loads of 24 consecutive floats).
template <int k>
inline __m256 component(__m256 a, __m256 b, __m256 c) {
    // where component k of triple `lane` is, float 3·lane + k of the 24: in A, B or C (a lane
    // another source fills holds 0, which is also the right index where the table shows 0)
    alignas(32) static constexpr std::int32_t kIndex[3][3][8] = {
        {{0, 3, 6, 0, 0, 0, 0, 0}, {0, 0, 0, 1, 4, 7, 0, 0}, {0, 0, 0, 0, 0, 0, 2, 5}},
        {{1, 4, 7, 0, 0, 0, 0, 0}, {0, 0, 0, 2, 5, 0, 0, 0}, {0, 0, 0, 0, 0, 0, 3, 6}},
        {{2, 5, 0, 0, 0, 0, 0, 0}, {0, 0, 0, 3, 6, 0, 0, 0}, {0, 0, 0, 0, 0, 1, 4, 7}},
    };
    // x: A 0-2, B 3-5, C 6-7; y: A 0-2, B 3-4, C 5-7; z: A 0-1, B 2-4, C 5-7
    // (plain constants, not array elements: GCC with sanitizers did not fold those to the blend's
    // immediate)
    constexpr int kTakeB = k == 0 ? 0b00111000 : k == 1 ? 0b00011000 : 0b00011100;
    constexpr int kTakeC = k == 0 ? 0b11000000 : 0b11100000;
    const auto index = [](const std::int32_t* p) { return _mm256_load_si256(reinterpret_cast<const __m256i*>(p)); };
    __m256 r = _mm256_permutevar8x32_ps(a, index(kIndex[k][0]));
    r = _mm256_blend_ps(r, _mm256_permutevar8x32_ps(b, index(kIndex[k][1])), kTakeB);
    return _mm256_blend_ps(r, _mm256_permutevar8x32_ps(c, index(kIndex[k][2])), kTakeC);
}

}  // namespace

std::uint32_t prepare_rays_vector(const float* origins, const float* directions, const float* tmax_of, float tmin,
                                  float tmax, std::uint32_t n, Ray* rays, float* t_scale, std::uint8_t* octant,
                                  std::uint32_t& refused) {
    const __m256i magnitude = _mm256_set1_epi32(0x7fffffff);
    // the bounds of ray_batch.h prepare_piece, as signed integers (every magnitude's bits are
    // below 2^31, a NaN's above every number's)
    const __m256i max_origin = _mm256_set1_epi32(std::int32_t(kMaxCoordinateBits)),
                  least = _mm256_set1_epi32(std::int32_t(kMinDirectionBits)),
                  most = _mm256_set1_epi32(std::int32_t(kMaxDirectionBits));
    __m256i bad = _mm256_setzero_si256();
    std::uint32_t j = 0;
    for (; j + 8 <= n; j += 8) {
        const float *o = origins + 3 * j, *d = directions + 3 * j;
        const __m256 oa = _mm256_loadu_ps(o), ob = _mm256_loadu_ps(o + 8), oc = _mm256_loadu_ps(o + 16);
        const __m256 da = _mm256_loadu_ps(d), db = _mm256_loadu_ps(d + 8), dc = _mm256_loadu_ps(d + 16);
        const __m256 ox = component<0>(oa, ob, oc), oy = component<1>(oa, ob, oc), oz = component<2>(oa, ob, oc);
        const __m256 dx = component<0>(da, db, dc), dy = component<1>(da, db, dc), dz = component<2>(da, db, dc);
        const auto bits = [&](__m256 x) { return _mm256_and_si256(_mm256_castps_si256(x), magnitude); };
        const __m256i origin = _mm256_max_epi32(bits(ox), _mm256_max_epi32(bits(oy), bits(oz)));
        const __m256i dir = _mm256_max_epi32(bits(dx), _mm256_max_epi32(bits(dy), bits(dz)));
        bad = _mm256_or_si256(bad, _mm256_cmpgt_epi32(origin, max_origin));
        bad = _mm256_or_si256(bad, _mm256_or_si256(_mm256_cmpgt_epi32(least, dir), _mm256_cmpgt_epi32(dir, most)));
        __m256 far = _mm256_set1_ps(tmax);
        if (tmax_of) {
            far = _mm256_loadu_ps(tmax_of + j);
            bad = _mm256_or_si256(bad, _mm256_castps_si256(_mm256_cmp_ps(far, _mm256_setzero_ps(), _CMP_NGE_UQ)));
        }
        // coordinate_range.h scale_ray_by: e = exponent − 126, down = 2^−e, up = 2^e; where e = 0 the
        // scalar pass leaves the fields as they are, so they are kept there rather than multiplied
        // by 1 (which would flush a denormal under denormals-are-zero)
        const __m256i exponent = _mm256_srli_epi32(dir, 23);
        const __m256 down =
            _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_sub_epi32(_mm256_set1_epi32(253), exponent), 23));
        const __m256 up = _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_add_epi32(exponent, _mm256_set1_epi32(1)), 23));
        const __m256 keep = _mm256_castsi256_ps(_mm256_cmpeq_epi32(exponent, _mm256_set1_epi32(126)));
        const auto scaled = [keep](__m256 x, __m256 by) { return _mm256_blendv_ps(_mm256_mul_ps(x, by), x, keep); };
        const __m256 sx = scaled(dx, down), sy = scaled(dy, down), sz = scaled(dz, down);
        const __m256 near = scaled(_mm256_set1_ps(tmin), up);
        far = scaled(far, up);
        _mm256_storeu_ps(t_scale + j, down);
        // the octant: bit a set where dir[a]'s sign bit is (wide_kernel.h octant_of_bits), to bytes
        const __m256i sign_x = _mm256_srli_epi32(_mm256_castps_si256(dx), 31);
        const __m256i sign_y = _mm256_slli_epi32(_mm256_srli_epi32(_mm256_castps_si256(dy), 31), 1);
        const __m256i sign_z = _mm256_slli_epi32(_mm256_srli_epi32(_mm256_castps_si256(dz), 31), 2);
        const __m256i oct = _mm256_or_si256(sign_x, _mm256_or_si256(sign_y, sign_z));
        const __m128i words = _mm_packus_epi32(_mm256_castsi256_si128(oct), _mm256_extracti128_si256(oct, 1));
        _mm_storel_epi64(reinterpret_cast<__m128i*>(octant + j), _mm_packus_epi16(words, words));
        // the eight fields' vectors to eight rays (row k is ray j + k)
        __m256 row[8] = {ox, oy, oz, sx, sy, sz, near, far};
        transpose8(row);
        for (int k = 0; k < 8; ++k) _mm256_storeu_ps(reinterpret_cast<float*>(rays + j + k), row[k]);
    }
    refused |= std::uint32_t(!_mm256_testz_si256(bad, bad));
    return j;
}

std::uint32_t ray_keys(const float* origins, const float* directions, std::uint32_t n, const float lo[3],
                       const float scale[3], float top, int bits, std::uint16_t* key) {
    const __m256 zero = _mm256_setzero_ps(), highest = _mm256_set1_ps(top);
    // the cell on each axis as RayKeys::operator() makes it: (o − lo) · scale truncated, below 0
    // (or NaN: the comparison is false) cell 0, from `top` on `top`; its bits spread three apart
    const auto cell = [&](__m256 o, int a) {
        const __m256 x = _mm256_mul_ps(_mm256_sub_ps(o, _mm256_set1_ps(lo[a])), _mm256_set1_ps(scale[a]));
        const __m256i c = _mm256_and_si256(_mm256_cvttps_epi32(_mm256_min_ps(x, highest)),
                                           _mm256_castps_si256(_mm256_cmp_ps(x, zero, _CMP_GT_OQ)));
        // b3 b2 b1 b0 → b0 at bit 0, b1 at 3, b2 at 6, b3 at 9 (kSpread)
        const __m256i x4 = _mm256_and_si256(_mm256_or_si256(c, _mm256_slli_epi32(c, 4)), _mm256_set1_epi32(0x0C3));
        const __m256i x2 = _mm256_and_si256(_mm256_or_si256(x4, _mm256_slli_epi32(x4, 2)), _mm256_set1_epi32(0x249));
        return _mm256_slli_epi32(x2, a);
    };
    std::uint32_t j = 0;
    for (; j + 8 <= n; j += 8) {
        const float *o = origins + 3 * std::size_t(j), *d = directions + 3 * std::size_t(j);
        const __m256 oa = _mm256_loadu_ps(o), ob = _mm256_loadu_ps(o + 8), oc = _mm256_loadu_ps(o + 16);
        const __m256 da = _mm256_loadu_ps(d), db = _mm256_loadu_ps(d + 8), dc = _mm256_loadu_ps(d + 16);
        const __m256i sign_x = _mm256_srli_epi32(_mm256_castps_si256(component<0>(da, db, dc)), 31);
        const __m256i sign_y = _mm256_srli_epi32(_mm256_castps_si256(component<1>(da, db, dc)), 31);
        const __m256i sign_z = _mm256_srli_epi32(_mm256_castps_si256(component<2>(da, db, dc)), 31);
        const __m256i octant =
            _mm256_or_si256(sign_x, _mm256_or_si256(_mm256_slli_epi32(sign_y, 1), _mm256_slli_epi32(sign_z, 2)));
        const __m256i k = _mm256_or_si256(
            _mm256_or_si256(cell(component<0>(oa, ob, oc), 0), cell(component<1>(oa, ob, oc), 1)),
            _mm256_or_si256(cell(component<2>(oa, ob, oc), 2), _mm256_sll_epi32(octant, _mm_cvtsi32_si128(3 * bits))));
        // below 2^15: the 16-bit lanes of a signed pack hold them as they are
        const __m128i words = _mm_packs_epi32(_mm256_castsi256_si128(k), _mm256_extracti128_si256(k, 1));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(key + j), words);
    }
    return j;
}

static_assert(sizeof(Hit) == 5 * sizeof(float) && offsetof(Hit, ref) == 4 && offsetof(Hit, u) == 8 &&
                  offsetof(Hit, v) == 12,
              "a Hit is five words: t, ref, u, v, slot");

std::uint32_t write_hits(float* t, std::int32_t* prim, std::uint8_t* kind, float* u, float* v,
                         std::uint32_t* nodes_visited, std::uint32_t n, const Hit* hits, const std::uint32_t* visited,
                         const float* t_scale) {
    const __m256i stride = _mm256_setr_epi32(0, 5, 10, 15, 20, 25, 30, 35);  // a Hit is five words
    const __m256i no_hit = _mm256_set1_epi32(std::int32_t(kNoHit));
    const __m256i sphere_bit = _mm256_set1_epi32(std::int32_t(gpu::REF_SPHERE_BIT));
    std::uint32_t written = 0;
    for (std::uint32_t j = 0; j + 8 <= n; j += 8) {
        const float* at = reinterpret_cast<const float*>(hits + j);
        const __m256i ref = _mm256_i32gather_epi32(reinterpret_cast<const int*>(at) + 1, stride, 4);
        const __m256i miss = _mm256_cmpeq_epi32(ref, no_hit);
        // a sphere's hit (the bit set, not a miss) is finished by the scalar loop: its eight left
        const __m256i sphere =
            _mm256_andnot_si256(miss, _mm256_cmpeq_epi32(_mm256_and_si256(ref, sphere_bit), sphere_bit));
        if (!_mm256_testz_si256(sphere, sphere)) continue;
        const __m256 hit_t = _mm256_i32gather_ps(at, stride, 4);
        const __m256 scaled = _mm256_mul_ps(hit_t, _mm256_loadu_ps(t_scale + j));
        _mm256_storeu_ps(t + j, _mm256_blendv_ps(scaled, _mm256_set1_ps(kInfinity), _mm256_castsi256_ps(miss)));
        // the index as it is (no sphere bit here), a miss's kNoHit as it is: −1
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(prim + j), ref);
        if (kind) _mm_storel_epi64(reinterpret_cast<__m128i*>(kind + j), _mm_setzero_si128());  // triangles, misses: 0
        if (u) _mm256_storeu_ps(u + j, _mm256_i32gather_ps(at + 2, stride, 4));
        if (v) _mm256_storeu_ps(v + j, _mm256_i32gather_ps(at + 3, stride, 4));
        if (nodes_visited)
            _mm256_storeu_si256(reinterpret_cast<__m256i*>(nodes_visited + j),
                                _mm256_loadu_si256(reinterpret_cast<const __m256i*>(visited + j)));
        written |= 1u << (j / 8);
    }
    return written;
}

}  // namespace bvhlab::BVHLAB_KERNEL_NS
