// packing.cpp — the one packing of primitives for the ray tests (geometry.h PackedPrim), used by
// the CPU traversal's leaf-ordered array and the tracer's triangle array (render_scene.cpp).
#include <algorithm>
#include <cstddef>

#include "bvhlab/geometry.h"
#include "bvhlab/simd.h"
#include "bvhlab/thread_pool.h"

namespace bvhlab {
namespace {

gpu::vec3 v3(Vec3 v) { return {v.x, v.y, v.z}; }

#ifdef BVHLAB_SSE
/// pack_triangle with SSE: the same products and differences lane by lane, so the same zero test.
/// The third vertex is loaded from v + 5 and shifted down, so no load reads past the triangle.
/// Lane 3 of each row (material, ref, 0) is set in the register and each row stored once: storing
/// the rows and then those fields alone made the next read of the record wait (a failed
/// store-to-load forwarding, a third of the packing's time).
inline void pack_triangle_into(PackedPrim* dst, const float* v, std::uint32_t index, std::uint32_t material) {
    __m128 a = _mm_loadu_ps(v), b = _mm_loadu_ps(v + 3), c = _mm_loadu_ps(v + 5);
    c = _mm_shuffle_ps(c, c, _MM_SHUFFLE(0, 3, 2, 1));
    const __m128 e1 = _mm_sub_ps(b, a), e2 = _mm_sub_ps(c, a);
    // n = e1 × e2 = (e1.y e2.z - e1.z e2.y, e1.z e2.x - e1.x e2.z, e1.x e2.y - e1.y e2.x)
    const __m128 n = _mm_sub_ps(
        _mm_mul_ps(_mm_shuffle_ps(e1, e1, _MM_SHUFFLE(3, 0, 2, 1)), _mm_shuffle_ps(e2, e2, _MM_SHUFFLE(3, 1, 0, 2))),
        _mm_mul_ps(_mm_shuffle_ps(e1, e1, _MM_SHUFFLE(3, 1, 0, 2)), _mm_shuffle_ps(e2, e2, _MM_SHUFFLE(3, 0, 2, 1))));
    if ((_mm_movemask_ps(_mm_cmpeq_ps(n, _mm_setzero_ps())) & 7) == 7) b = c = a;  // zero area: never hit
    static_assert(sizeof(PackedPrim) == 48 && offsetof(PackedPrim, material) == 12 && offsetof(PackedPrim, ref) == 28);
    const __m128 xyz = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
    const auto lane3 = [&](__m128 row, std::uint32_t w) {
        return _mm_or_ps(_mm_and_ps(row, xyz), _mm_castsi128_ps(_mm_set_epi32(int(w), 0, 0, 0)));
    };
    float* rows = reinterpret_cast<float*>(dst);  // v0, material | v1, ref | v2, unused
    _mm_storeu_ps(rows, lane3(a, material)), _mm_storeu_ps(rows + 4, lane3(b, index));
    _mm_storeu_ps(rows + 8, _mm_and_ps(c, xyz));
}
#else
inline void pack_triangle_into(PackedPrim* dst, const float* v, std::uint32_t index, std::uint32_t material) {
    Vec3 v0{v[0], v[1], v[2]}, v1{v[3], v[4], v[5]}, v2{v[6], v[7], v[8]};
    const Vec3 n = cross(v1 - v0, v2 - v0);
    if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) v1 = v2 = v0;  // zero area: never hit
    *dst = {v3(v0), material, v3(v1), index, v3(v2), 0};
}
#endif

PackedPrim pack_sphere(const GeometryView& g, std::uint32_t ref) {
    const std::size_t i = ref_index(ref);
    return {v3(g.sphere_center(i)), 0, {g.sphere_radius(i), 0, 0}, ref, {}, 0};
}

inline void pack_prim_into(PackedPrim* dst, const GeometryView& g, std::uint32_t ref) {
    if (is_sphere_ref(ref)) *dst = pack_sphere(g, ref);
    else pack_triangle_into(dst, g.triangles + 9 * std::size_t(ref_index(ref)), ref_index(ref), 0);
}

}  // namespace

PackedPrim pack_triangle(const GeometryView& g, std::size_t i, std::uint32_t material) {
    PackedPrim out;
    pack_triangle_into(&out, g.triangles + 9 * i, static_cast<std::uint32_t>(i), material);
    return out;
}

PackedPrim pack_prim(const GeometryView& g, std::uint32_t ref) {
    PackedPrim out;
    pack_prim_into(&out, g, ref);
    return out;
}

void pack_run(const GeometryView& g, const std::uint32_t* refs, std::size_t count, PackedPrim* out, bool fetched) {
    if (fetched) {
        for (std::size_t k = 0; k < count; ++k) pack_prim_into(out + k, g, refs[k]);
        return;
    }
    // Leaf order visits the input at random: each read would wait on memory, so the input of the
    // reference kAhead places later is fetched while this one is packed (Sponza: the packing
    // took 22% of an LBVH build before).
    constexpr std::size_t kAhead = 12;
    for (std::size_t k = 0; k < std::min(count, kAhead); ++k) prefetch_prim(g, refs[k]);
    for (std::size_t k = 0; k < count; ++k) {
        if (k + kAhead < count) prefetch_prim(g, refs[k + kAhead]);
        pack_prim_into(out + k, g, refs[k]);
    }
}

BigVector<PackedPrim> pack_prims(const GeometryView& g, const BigVector<std::uint32_t>& refs, unsigned threads) {
    BigVector<PackedPrim> out(refs.size());
    constexpr std::size_t kChunk = 1 << 15;
    ThreadPool::shared().run((refs.size() + kChunk - 1) / kChunk, threads, [&](std::size_t c, unsigned) {
        const std::size_t begin = c * kChunk, end = std::min(refs.size(), begin + kChunk);
        pack_run(g, refs.data() + begin, end - begin, out.data() + begin);
    });
    return out;
}

}  // namespace bvhlab
