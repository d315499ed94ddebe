// packing.cpp — the one packing of primitives for the ray tests (geometry.h PackedPrim), used by
// the CPU traversal's leaf-ordered array and the tracer's triangle array (render_scene.cpp).
#include <algorithm>
#include <cstddef>

#include "bvhlab/geometry.h"
#include "bvhlab/simd.h"
#include "bvhlab/thread_pool.h"
#include "pack_triangle.h"

namespace bvhlab {
namespace {

gpu::vec3 v3(Vec3 v) { return {v.x, v.y, v.z}; }

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
