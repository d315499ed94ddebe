// pack_triangle.h — the one packing of a triangle for the ray tests (geometry.h PackedPrim), inline
// for the loops that pack millions of them: pack_run (packing.cpp) and the refit (refit.cpp),
// which also takes the triangle's box from the vertices loaded here.
#pragma once
#include <cstddef>
#include <cstdint>

#include "bvhlab/geometry.h"
#include "bvhlab/simd.h"

namespace bvhlab {

#ifdef BVHLAB_SSE
/// Packs the triangle whose nine floats are at `v` into `dst` (reference `index`, `material`), and
/// gives its vertices as read (lane 3 zero; a zero-area triangle's too, though it is packed as
/// three copies of its first vertex). The same products and differences lane by lane as the
/// scalar version, so the same zero test. The third vertex is loaded from v + 5 and shifted down,
/// so no load reads past the triangle. Returns whether it was packed as a point (zero area). Lane 3 of each row (material, ref, 0) is set in the
/// register and each row stored once: storing the rows and then those fields alone made the next
/// read of the record wait (a failed store-to-load forwarding, a third of the packing's time).
inline bool pack_triangle_rows(PackedPrim* dst, const float* v, std::uint32_t index, std::uint32_t material, F4& v0,
                               F4& v1, F4& v2) {
    __m128 a = _mm_loadu_ps(v), b = _mm_loadu_ps(v + 3), c = _mm_loadu_ps(v + 5);
    c = _mm_shuffle_ps(c, c, _MM_SHUFFLE(0, 3, 2, 1));
    const __m128 xyz = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
    v0.v = _mm_and_ps(a, xyz), v1.v = _mm_and_ps(b, xyz), v2.v = _mm_and_ps(c, xyz);
    const __m128 e1 = _mm_sub_ps(b, a), e2 = _mm_sub_ps(c, a);
    // n = e1 × e2 = (e1.y e2.z - e1.z e2.y, e1.z e2.x - e1.x e2.z, e1.x e2.y - e1.y e2.x)
    const __m128 n = _mm_sub_ps(
        _mm_mul_ps(_mm_shuffle_ps(e1, e1, _MM_SHUFFLE(3, 0, 2, 1)), _mm_shuffle_ps(e2, e2, _MM_SHUFFLE(3, 1, 0, 2))),
        _mm_mul_ps(_mm_shuffle_ps(e1, e1, _MM_SHUFFLE(3, 1, 0, 2)), _mm_shuffle_ps(e2, e2, _MM_SHUFFLE(3, 0, 2, 1))));
    const bool point = (_mm_movemask_ps(_mm_cmpeq_ps(n, _mm_setzero_ps())) & 7) == 7;
    if (point) b = c = a;  // zero area: never hit
    static_assert(sizeof(PackedPrim) == 48 && offsetof(PackedPrim, material) == 12 && offsetof(PackedPrim, ref) == 28);
    const auto lane3 = [&](__m128 row, std::uint32_t w) {
        return _mm_or_ps(_mm_and_ps(row, xyz), _mm_castsi128_ps(_mm_set_epi32(int(w), 0, 0, 0)));
    };
    float* rows = reinterpret_cast<float*>(dst);  // v0, material | v1, ref | v2, unused
    _mm_storeu_ps(rows, lane3(a, material)), _mm_storeu_ps(rows + 4, lane3(b, index));
    _mm_storeu_ps(rows + 8, _mm_and_ps(c, xyz));
    return point;
}
#else
inline bool pack_triangle_rows(PackedPrim* dst, const float* v, std::uint32_t index, std::uint32_t material, F4& v0,
                               F4& v1, F4& v2) {
    Vec3 a{v[0], v[1], v[2]}, b{v[3], v[4], v[5]}, c{v[6], v[7], v[8]};
    v0 = F4::set3(a.x, a.y, a.z), v1 = F4::set3(b.x, b.y, b.z), v2 = F4::set3(c.x, c.y, c.z);
    const Vec3 n = cross(b - a, c - a);
    const bool point = n.x == 0.0f && n.y == 0.0f && n.z == 0.0f;
    if (point) b = c = a;  // zero area: never hit
    *dst = {{a.x, a.y, a.z}, material, {b.x, b.y, b.z}, index, {c.x, c.y, c.z}, 0};
    return point;
}
#endif

/// pack_triangle_rows without the vertices.
inline void pack_triangle_into(PackedPrim* dst, const float* v, std::uint32_t index, std::uint32_t material) {
    F4 a, b, c;
    pack_triangle_rows(dst, v, index, material, a, b, c);
}

}  // namespace bvhlab
