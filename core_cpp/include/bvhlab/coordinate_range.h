// coordinate_range.h — the coordinates and ray directions for which bvhlab's float32 ray tests
// cannot overflow, and the exact rescaling that makes any direction length safe.
//
// Why a range at all: every test is float32 arithmetic, and products of coordinates grow like
// their cube. Outside this range a hit is silently lost (a 1e13 triangle, a 2e19 sphere, a ray
// direction of length 1e-28 used to miss everything). Inside it nothing can overflow:
//
// Let every point — vertices, sphere extents (centre ± radius), ray origins — lie in [-L, L]³
// with L = kMaxCoordinate = 2^40 ≈ 1.1e12, and let the ray direction d be scaled by a power of
// two so that its largest component lies in [0.5, 1) (scale_ray below; exact, see there), so
// every |d_i| < 1 and |d|² < 3. Then:
//  - Möller–Trumbore (ray.h hit_triangle): e1, e2 and s = origin - v0 are differences of two
//    points, components ≤ 2L = 2^41; p = d × e2 ≤ 2·2^41 = 2^42; det = e1·p and u·det = s·p
//    ≤ 3·2^41·2^42 < 2^85; q = s × e1 ≤ 2·2^41·2^41 = 2^83; v·det = d·q < 2^85; and the largest
//    product, t·det = e2·q ≤ 3·2^41·2^83 < 2^126, stays below FLT_MAX ≈ 2^128. (With L = 2^41 the
//    bound is 3·2^127 > FLT_MAX: 2^40 is the largest power of two that is safe.) A hit's t is a
//    distance over |d| ≤ 2√3·L / 0.5 < 2^43, so t = (t·det)/det cannot overflow either.
//  - Sphere quadratic (hit_sphere): oc = origin - centre ≤ 2^41; a = d·d < 3 (and ≥ 0.25, so it
//    never underflows, which an unscaled |d| = 1e-20 did: a = 1e-40 is subnormal);
//    b = oc·d < 2^43; c = oc·oc - r² < 2^84; b² and a·c < 2^86.
//  - Slab test (hit_box): (plane - origin) ≤ 2^41 times 1/d_i. For a (nearly) parallel axis 1/d_i
//    is huge or ±inf and the product may overflow to ±inf: that is the right answer (the slab
//    puts no limit, or excludes the ray, on that side), and 0·inf = NaN on a face is ignored by
//    raise_to/lower_to. The slab test only compares, so infinities are safe there.
// Spheres: a radius of at least kMinRadius = 2^-60 keeps r² ≥ 2^-120 a normal float. A smaller
// one underflows: c = |oc|² - r² then rounds to 0 for a ray passing ~1e-37 away, and the quadratic
// counts that as a hit (the fuzzer found a 7e-41 sphere "hit" from 4e-37 away).
// Small scenes: the watertight triangle test (geometry.glsl hit_triangle, the wide walks') makes
// t·det as a sum of products of three coordinates relative to the ray's origin, which shrink like
// the cube of the scene's size s: below s ≈ 2^-42 they leave float32's normal range, lose their
// bits and then flush to zero (random triangles at 1e-13 gave 5 of 5,000 rays the wrong triangle,
// at 1e-14 1,865, at 1e-15 all but 2 missed). A tree whose primitives' box spans less than
// kMinExtent = 2^-32 on its largest side is refused when it holds triangles (spheres alone keep
// working down to kMinRadius); at 2^-32, triangles down to 2^-15 of the scene's size keep every
// product normal. A box of no extent (every triangle at one point: none can be hit) is allowed.
// Directions: the rescaled t is t' · 2^-e where d's largest component is f·2^e, f in [0.5, 1).
// With that component in [kMinDirection, kMaxDirection] = [2^-80, 2^80], t ≤ 2^43 · 2^80 = 2^123
// cannot overflow (below about 2^-84 it could), and a hit farther than 2^-45 from the origin of
// the ray keeps a normal (not subnormal) t even for the longest directions.
#pragma once
#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "bvhlab/ray.h"
#include "bvhlab/vec3.h"

namespace bvhlab {

inline constexpr float kMaxCoordinate = 0x1p40f;  ///< |x| ≤ 2^40 ≈ 1.0995e12 for every point
inline constexpr float kMinDirection = 0x1p-80f;  ///< smallest allowed largest |component| of a direction
inline constexpr float kMaxDirection = 0x1p80f;   ///< largest allowed largest |component| of a direction
/// The three bounds' bits: the batch checks compare the bits of |x| with them (ray_batch.h
/// prepare_piece, its vector pass), a NaN's bits above every number's.
inline constexpr std::uint32_t kMaxCoordinateBits = std::bit_cast<std::uint32_t>(kMaxCoordinate);
inline constexpr std::uint32_t kMinDirectionBits = std::bit_cast<std::uint32_t>(kMinDirection);
inline constexpr std::uint32_t kMaxDirectionBits = std::bit_cast<std::uint32_t>(kMaxDirection);
inline constexpr float kMinRadius = 0x1p-60f;  ///< smallest sphere radius (≈ 8.7e-19)
inline constexpr float kMinExtent = 0x1p-32f;  ///< smallest largest side of a tree's box with triangles (≈ 2.3e-10)

// The two rules below are written with `&` rather than `&&` so that they compile without branches
// (a NaN fails every comparison; |x| <= FLT_MAX is x finite): check_rays runs them on every ray of
// a batch (Sponza random rays through intersect_batch: 48 instructions and 9 branches a ray with
// branches).

/// True when every component of p lies in [-kMaxCoordinate, kMaxCoordinate] (false for NaN).
inline bool in_coordinate_range(Vec3 p) {
    return (std::fabs(p.x) <= kMaxCoordinate) & (std::fabs(p.y) <= kMaxCoordinate) & (std::fabs(p.z) <= kMaxCoordinate);
}

/// The largest |component| of d.
inline float largest_component(Vec3 d) { return std::max(std::fabs(d.x), std::max(std::fabs(d.y), std::fabs(d.z))); }

/// True when d's largest |component| lies in [kMinDirection, kMaxDirection] (false for NaN, 0, inf).
inline bool direction_in_range(Vec3 d) {
    const float m = largest_component(d);  // may ignore a NaN component: the finiteness test catches it
    return (m >= kMinDirection) & (m <= kMaxDirection) & (std::fabs(d.x) <= FLT_MAX) & (std::fabs(d.y) <= FLT_MAX) &
           (std::fabs(d.z) <= FLT_MAX);
}

/// 2^e for e in [-126, 127], made from its bits (exact, no library call).
inline float power_of_two(int e) {
    const auto bits = std::uint32_t(127 + e) << 23;
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

/// scale_ray (below) for a direction in range whose largest |component| has the bits `largest_bits` (a
/// batch's rays have them from their check: ray_batch.h prepare_piece).
inline float scale_ray_by(Ray& ray, std::uint32_t largest_bits) {
    const int e = int(largest_bits >> 23) - 126;                // m = f·2^e with f in [0.5, 1): m is normal here
    if (e == 0) return 1.0f;                                    // already in [0.5, 1): nothing to do
    const float down = power_of_two(-e), up = power_of_two(e);  // e in [-79, 81]: both normal
    ray.dir = ray.dir * down;
    ray.tmin *= up;
    ray.tmax *= up;
    return down;
}

/// Scales a ray's direction by 2^-e so that its largest component lies in [0.5, 1), and its
/// (tmin, tmax) by 2^e, so it describes the same points; returns 2^-e, by which the t of a hit
/// must be multiplied to be in the caller's units. Powers of two scale exactly, and every test is
/// homogeneous in d (Möller–Trumbore's u, v and the sphere's roots are ratios), so the hit,
/// u, v and t are bit for bit what the unscaled arithmetic gives whenever that does not over- or
/// underflow; and where it would, the scaled arithmetic stays in range (see the top of this file).
/// Needs direction_in_range(dir) (a direction outside it is left as it is). e comes from the
/// largest component's exponent bits and 2^±e from bits (power_of_two), which is what frexp and
/// ldexp give for a normal float (a product with a power of two is rounded once, as ldexp's
/// result is) without their library calls: every ray of a batch and every instance a two-level
/// ray enters is scaled (two-level random rays: 17 instructions a ray in frexpf alone).
inline float scale_ray(Ray& ray) {
    const float m = largest_component(ray.dir);
    if (!(m >= kMinDirection && m <= kMaxDirection)) return 1.0f;
    std::uint32_t bits;
    std::memcpy(&bits, &m, sizeof bits);
    return scale_ray_by(ray, bits);
}

}  // namespace bvhlab
