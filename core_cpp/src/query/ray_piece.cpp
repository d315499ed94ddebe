// prepare_rays_vector, write_hits_vector (ray_batch.h) and RayKeys::of_rays (ray_order.h): the
// batch's vector passes over the caller's rays and over a piece's hits on the active instruction
// set (isa.h), or none (the scalar loops of prepare_piece, write_hits and of_rays then do all the
// work).
#include <cstdint>

#include "bvhlab/isa.h"
#include "ray_batch.h"

namespace bvhlab {

/// The batch's vector passes of ray_piece_avx2.cpp's builds, in namespace `ns` (avx2, avx512).
#define BVHLAB_DECLARE_RAY_PIECE(ns)                                                                                   \
    namespace ns {                                                                                                     \
    std::uint32_t prepare_rays_vector(const float* origins, const float* directions, const float* tmax_of, float tmin, \
                                      float tmax, std::uint32_t n, Ray* rays, float* t_scale, std::uint8_t* octant,    \
                                      std::uint32_t& refused);                                                         \
    std::uint32_t write_hits(float* t, std::int32_t* prim, std::uint8_t* kind, float* u, float* v,                     \
                             std::uint32_t* nodes_visited, std::uint32_t n, const Hit* hits,                           \
                             const std::uint32_t* visited, const float* t_scale);                                      \
    std::uint32_t ray_keys(const float* origins, const float* directions, std::uint32_t n, const float lo[3],          \
                           const float scale[3], float top, int bits, std::uint16_t* key);                             \
    }
BVHLAB_DECLARE_RAY_PIECE(avx2)
BVHLAB_DECLARE_RAY_PIECE(avx512)
#undef BVHLAB_DECLARE_RAY_PIECE

void RayKeys::of_rays(const float* origins, const float* directions, std::uint32_t n, std::uint16_t* key) const {
    std::uint32_t j = 0;
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() == Isa::Avx2) j = avx2::ray_keys(origins, directions, n, lo, scale, top, bits, key);
#endif
#if defined(BVHLAB_AVX512_KERNELS)
    if (active_isa() == Isa::Avx512) j = avx512::ray_keys(origins, directions, n, lo, scale, top, bits, key);
#endif
    for (; j < n; ++j) key[j] = std::uint16_t((*this)(origins + 3 * std::size_t(j), directions + 3 * std::size_t(j)));
}

std::uint32_t prepare_rays_vector(const float* origins, const float* directions, const float* tmax_of, float tmin,
                                  float tmax, std::uint32_t n, Ray* rays, float* t_scale, std::uint8_t* octant,
                                  std::uint32_t& refused) {
#if defined(BVHLAB_AVX512_KERNELS)
    if (active_isa() == Isa::Avx512)
        return avx512::prepare_rays_vector(origins, directions, tmax_of, tmin, tmax, n, rays, t_scale, octant, refused);
#endif
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() == Isa::Avx2)
        return avx2::prepare_rays_vector(origins, directions, tmax_of, tmin, tmax, n, rays, t_scale, octant, refused);
#endif
    (void)origins, (void)directions, (void)tmax_of, (void)tmin, (void)tmax, (void)n, (void)rays, (void)t_scale;
    (void)octant, (void)refused;
    return 0;
}

std::uint32_t write_hits_vector(const HitBatch& out, std::size_t begin, std::uint32_t n, const Hit* hits,
                                const std::uint32_t* visited, const float* t_scale) {
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() >= Isa::Avx2) {
        n = n < 256 ? n : 256;  // a bit an eight in the answer: the rest to the scalar loop
        const auto at = [begin](auto* p) { return p ? p + begin : p; };
#if defined(BVHLAB_AVX512_KERNELS)
        if (active_isa() == Isa::Avx512)
            return avx512::write_hits(out.t + begin, out.prim + begin, at(out.kind), at(out.u), at(out.v),
                                      at(out.nodes_visited), n, hits, visited, t_scale);
#endif
        return avx2::write_hits(out.t + begin, out.prim + begin, at(out.kind), at(out.u), at(out.v),
                                at(out.nodes_visited), n, hits, visited, t_scale);
    }
#endif
    (void)out, (void)begin, (void)n, (void)hits, (void)visited, (void)t_scale;
    return 0;
}

}  // namespace bvhlab
