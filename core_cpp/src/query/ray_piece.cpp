// prepare_rays (ray_batch.h): the batch's vector pass over the caller's rays on the active
// instruction set (isa.h), or none (the scalar pass of prepare_piece then reads every ray).
#include <cstdint>

#include "bvhlab/isa.h"
#include "ray_batch.h"

namespace bvhlab {

#if defined(BVHLAB_AVX2_KERNELS)
namespace avx2 {
std::uint32_t prepare_rays(const float* origins, const float* directions, const float* tmax_of, float tmin, float tmax,
                           std::uint32_t n, Ray* rays, float* t_scale, std::uint8_t* octant, std::uint32_t& refused);
}  // namespace avx2
#endif

std::uint32_t prepare_rays(const float* origins, const float* directions, const float* tmax_of, float tmin, float tmax,
                           std::uint32_t n, Ray* rays, float* t_scale, std::uint8_t* octant, std::uint32_t& refused) {
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() == Isa::Avx2)
        return avx2::prepare_rays(origins, directions, tmax_of, tmin, tmax, n, rays, t_scale, octant, refused);
#endif
    (void)origins, (void)directions, (void)tmax_of, (void)tmin, (void)tmax, (void)n, (void)rays, (void)t_scale;
    (void)octant, (void)refused;
    return 0;
}

}  // namespace bvhlab
