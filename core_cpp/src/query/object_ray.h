// object_ray.h — a world ray moved into an instance's object space (the two-level walks,
// traverse_two_level.cpp): origin and direction by the instance's ObjectColumns (transform.h),
// four lanes at once, and rescaled as every ray is (coordinate_range.h scale_ray).
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "bvhlab/coordinate_range.h"
#include "bvhlab/ray.h"
#include "bvhlab/simd.h"
#include "bvhlab/tlas.h"
#include "bvhlab/transform.h"

namespace bvhlab {

static_assert(offsetof(Ray, dir) == 3 * sizeof(float) && offsetof(Ray, tmin) == 6 * sizeof(float));

/// ray.origin = map.point(world.origin) and ray.dir = map.vector(world.dir), bit for bit: lane r
/// is ObjectColumns' row r, the same products summed in the same order ((x + y) + z; the build's
/// -ffp-contract=off keeps every product rounded on its own), after the same p - P. By rows the
/// 3×4 transform was 9 scalar products and 6 sums for each of the two, ~55 instructions an instance
/// (`many`, 2.7 instances a ray). tmin and tmax are the caller's to set.
inline void move_ray(const ObjectColumns& map, const Ray& world, Ray& ray) {
    const float* c = map.c.data();
    // lane 3 zeroed (load3): it holds the next column's first entry, and c[9] is P
    const F4 c0 = F4::load3(c), c1 = F4::load3(c + 3), c2 = F4::load3(c + 6);
    const auto times = [&](float x, float y, float z) {
        return (c0 * F4::splat(x) + c1 * F4::splat(y)) + c2 * F4::splat(z);
    };
    const Vec3 o = world.origin, d = world.dir;
    const F4 origin = times(o.x - c[9], o.y - c[10], o.z - c[11]), dir = times(d.x, d.y, d.z);
    // four lanes each: the origin's fourth on dir.x, written next; the direction's on tmin
    origin.store(&ray.origin.x);
    dir.store(&ray.dir.x);
}

/// direction_in_range and scale_ray (coordinate_range.h) of a moved ray in one pass over its
/// direction's bits: the largest |component|'s bits are the largest of the three |component|s'
/// bits as integers (their order is the magnitudes' for finite floats, and an infinity's or NaN's
/// lie above every finite one's, above kMaxDirectionBits), so one integer maximum gives both the
/// range test (one unsigned comparison) and scale_ray_by's exponent, where the two functions
/// found the largest component twice, by float maxima and five comparisons. False (the ray as it
/// was) where the direction is out of range; else `t_scale` is scale_ray's return.
inline bool scale_in_range(Ray& ray, float& t_scale) {
    std::uint32_t b[3];
    std::memcpy(b, &ray.dir, sizeof b);
    constexpr std::uint32_t kAbs = 0x7fffffffu;
    const std::uint32_t largest = std::max(b[0] & kAbs, std::max(b[1] & kAbs, b[2] & kAbs));
    if (largest - kMinDirectionBits > kMaxDirectionBits - kMinDirectionBits) return false;
    t_scale = scale_ray_by(ray, largest);
    return true;
}

/// The world ray (scaled already) up to `tmax` in the object space of instance `inst` (as a TLAS
/// leaf holds it, tlas.h LeafInstance), rescaled as the batch scales world rays, its scale in
/// `t_scale`: an identity instance walks the world ray as it is (no transform, nothing to
/// rescale: the one-mesh-and-movers layout of blender/motion.py, whose mesh 0 is such an
/// instance). False where the moved direction cannot be scaled (too long or short for float),
/// which cannot hit what lies within the range.
inline bool object_ray(const LeafInstance& inst, const Ray& world, float tmax, Ray& ray, float& t_scale) {
    t_scale = 1.0f;
    if (inst.identity) {
        ray = world, ray.tmax = tmax;
        return true;
    }
    move_ray(inst.to_object, world, ray);
    ray.tmin = world.tmin, ray.tmax = tmax;
    return scale_in_range(ray, t_scale);
}

}  // namespace bvhlab
