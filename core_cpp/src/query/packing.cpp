// packing.cpp — the one packing of primitives for the ray tests (geometry.h PackedPrim), used by
// the CPU traversal's leaf-ordered array and the tracer's triangle array (render_scene.cpp).
#include <algorithm>

#include "bvhlab/geometry.h"
#include "bvhlab/thread_pool.h"

namespace bvhlab {
namespace {

gpu::vec3 v3(Vec3 v) { return {v.x, v.y, v.z}; }

}  // namespace

PackedPrim pack_triangle(const GeometryView& g, std::size_t i, std::uint32_t material) {
    Vec3 v0 = g.vertex(i, 0), v1 = g.vertex(i, 1), v2 = g.vertex(i, 2);
    const Vec3 n = cross(v1 - v0, v2 - v0);
    if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) v1 = v2 = v0;  // zero area: never hit
    return {v3(v0), material, v3(v1), static_cast<std::uint32_t>(i), v3(v2), 0};
}

PackedPrim pack_prim(const GeometryView& g, std::uint32_t ref) {
    const std::size_t i = ref_index(ref);
    if (!is_sphere_ref(ref)) return pack_triangle(g, i);
    return {v3(g.sphere_center(i)), 0, {g.sphere_radius(i), 0, 0}, ref, {}, 0};
}

BigVector<PackedPrim> pack_prims(const GeometryView& g, const BigVector<std::uint32_t>& refs, unsigned threads) {
    BigVector<PackedPrim> out(refs.size());
    constexpr std::size_t kChunk = 1 << 15;
    // Leaf order visits the input at random: each read would wait on memory, so the input of the
    // reference kAhead places later is fetched while this one is packed (Sponza: the packing
    // took 22% of an LBVH build before).
    constexpr std::size_t kAhead = 12;
    auto prefetch = [&](std::uint32_t ref) {
        const std::size_t i = ref_index(ref);
        const float* p = is_sphere_ref(ref) ? g.spheres + 4 * i : g.triangles + 9 * i;
        __builtin_prefetch(p), __builtin_prefetch(p + 8);  // 36 bytes may span two lines
    };
    ThreadPool::shared().run((refs.size() + kChunk - 1) / kChunk, threads, [&](std::size_t c, unsigned) {
        const std::size_t begin = c * kChunk, end = std::min(refs.size(), begin + kChunk);
        for (std::size_t k = begin; k < std::min(end, begin + kAhead); ++k) prefetch(refs[k]);
        for (std::size_t k = begin; k < end; ++k) {
            if (k + kAhead < end) prefetch(refs[k + kAhead]);
            out[k] = pack_prim(g, refs[k]);
        }
    });
    return out;
}

}  // namespace bvhlab
