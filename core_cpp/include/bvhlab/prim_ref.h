// prim_ref.h — what the builders see of a primitive: its box and its reference, never its shape.
#pragma once
#include <cstdint>
#include "bvhlab/aabb.h"
#include "bvhlab/simd.h"
#include "gpu_types.h"

namespace bvhlab {

/// One primitive as the builders see it (32 bytes, so partitioning moves whole cache-line halves).
/// `ref` is the reference stored in the leaves (gpu::REF_SPHERE_BIT marks a sphere, report §5.1).
struct alignas(16) PrimRef {
    float lo[3];
    std::uint32_t ref;
    float hi[3];
    std::uint32_t code;  ///< Morton code of the centroid, written by the LBVH presort and read by split_lbvh
                         ///< only (the binned SAH recomputes a reference's bucket rather than storing
                         ///< it here, so a split method never writes its source range: split.h)

    float centroid(int axis) const { return 0.5f * (lo[axis] + hi[axis]); }
    Vec3 centroid() const { return {centroid(0), centroid(1), centroid(2)}; }
    Aabb box() const { return {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}}; }
    F4 lo4() const { return F4::load3(lo); }  ///< lane 3 = 0
    F4 hi4() const { return F4::load3(hi); }  ///< lane 3 = 0
};
static_assert(sizeof(PrimRef) == 32);

inline bool is_sphere_ref(std::uint32_t ref) { return (ref & gpu::REF_SPHERE_BIT) != 0; }
inline std::uint32_t ref_index(std::uint32_t ref) { return ref & gpu::REF_INDEX_MASK; }

}  // namespace bvhlab
