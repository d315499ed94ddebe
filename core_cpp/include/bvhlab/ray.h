// ray.h — rays, hits, and the ray-box / ray-primitive tests the CPU traversal uses.
#pragma once
#include <cmath>
#include <cstdint>
#include <limits>
#include "bvhlab/geometry.h"
#include "bvhlab/shared_geometry.h"
#include "gpu_types.h"

namespace bvhlab {

inline constexpr float kInfinity = std::numeric_limits<float>::infinity();
inline constexpr std::uint32_t kNoHit = 0xffffffffu;

/// A ray: points origin + t·dir for t in (tmin, tmax). dir need not be normalised. tmin >= 0 (the
/// batch queries refuse others, check_limits): the box test widens a box's far side by scaling its
/// distance, which holds only for distances >= 0.
struct Ray {
    Vec3 origin, dir;
    float tmin = 0.0f, tmax = kInfinity;
};

/// The closest hit: t = inf and ref = kNoHit on a miss. u, v: barycentrics of vertices 1 and 2
/// for triangles; for spheres, longitude / 2π and colatitude / π of the hit point.
struct Hit {
    float t = kInfinity;
    std::uint32_t ref = kNoHit;
    float u = 0.0f, v = 0.0f;
    std::uint32_t slot = kNoHit;  ///< position in the tree's leaf order (Bvh::refs, Bvh::prims)
};

/// A ray with what the tests need precomputed: the inverse direction of the box test and the
/// axes and shear of the watertight triangle test (geometry.glsl make_ray, the tracer's own).
struct RayQuery {
    gpu::TraceRay ray;

    /// The inverse direction is the exact IEEE inverse: ±inf for a zero component (see hit_box).
    explicit RayQuery(const Ray& r)
        : ray(gpu::make_ray({r.origin.x, r.origin.y, r.origin.z}, {r.dir.x, r.dir.y, r.dir.z}, r.tmin)) {}
};

/// `acc` raised to `t`, ignoring a NaN `t` (then `acc` is kept): the order of the comparison matters.
inline float raise_to(float acc, float t) { return t > acc ? t : acc; }
/// `acc` lowered to `t`, ignoring a NaN `t`.
inline float lower_to(float acc, float t) { return t < acc ? t : acc; }

/// Slab test (Kay and Kajiya 1986), closed on every face; on a hit, `t_enter` is where the ray
/// enters the box (clamped to tmin). A ray parallel to a slab has an infinite inverse direction:
/// inside the slab its planes give -inf and +inf (no constraint), outside both give the same
/// infinity (a miss), and exactly on a plane 0·inf = NaN, which raise_to/lower_to ignore, so a ray
/// lying in a face counts as inside: the box test agrees with the closed triangle test
/// (Williams et al. 2005; Barnes 2022, "Fast, branchless ray/bounding box intersections, part 3").
/// Conservative (Ize 2013): the far end, min(exits, tmax), is widened by gpu::BOX_FAR_SCALE.
inline bool hit_box(const gpu::BvhNode& n, const RayQuery& q, float tmax, float& t_enter) {
    const gpu::TraceRay& r = q.ray;
    const bool nx = std::signbit(r.inv_dir.x), ny = std::signbit(r.inv_dir.y), nz = std::signbit(r.inv_dir.z);
    const float near_x = ((nx ? n.hi.x : n.lo.x) - r.origin.x) * r.inv_dir.x;
    const float near_y = ((ny ? n.hi.y : n.lo.y) - r.origin.y) * r.inv_dir.y;
    const float near_z = ((nz ? n.hi.z : n.lo.z) - r.origin.z) * r.inv_dir.z;
    const float far_x = ((nx ? n.lo.x : n.hi.x) - r.origin.x) * r.inv_dir.x;
    const float far_y = ((ny ? n.lo.y : n.hi.y) - r.origin.y) * r.inv_dir.y;
    const float far_z = ((nz ? n.lo.z : n.hi.z) - r.origin.z) * r.inv_dir.z;
    const float t0 = raise_to(raise_to(raise_to(r.tmin, near_x), near_y), near_z);
    const float t1 = lower_to(lower_to(lower_to(tmax, far_x), far_y), far_z) * gpu::BOX_FAR_SCALE;
    t_enter = t0;
    return t0 <= t1;
}

/// Whether a box entered at `t_enter` may still hold a hit as near as `hit_t`: the test of a
/// stacked box at its pop, as conservative as hit_box (Ize 2013).
inline bool may_hold_closer(float t_enter, float hit_t) { return t_enter <= hit_t * gpu::BOX_FAR_SCALE; }

/// The closest-hit rule of every traversal, CPU and GPU (one rule, so that the three traversals
/// and the tracer agree when distances tie): a candidate at distance t in (tmin, tmax) replaces
/// the current hit when it is nearer, or as near and of a smaller primitive reference
/// (triangles before spheres, then the lower index).
inline bool closer_hit(float t, std::uint32_t ref, const Hit& hit) {
    return t < hit.t || (t == hit.t && hit.ref != kNoHit && ref < hit.ref);
}

/// The watertight triangle test (geometry.glsl hit_triangle) on a packed triangle; updates `hit`
/// when closer_hit() says so.
inline bool hit_triangle(const PackedPrim& p, const RayQuery& q, Hit& hit) {
    gpu::vec3 tuv;
    if (!gpu::hit_triangle(p.v0, p.v1, p.v2, q.ray, hit.t, tuv) || !closer_hit(tuv.x, p.ref, hit)) return false;
    hit.t = tuv.x, hit.ref = p.ref, hit.u = tuv.y, hit.v = tuv.z;
    return true;
}

/// The sphere test (geometry.glsl hit_sphere) on a packed sphere; u, v are filled in by finish_hit().
inline bool hit_sphere(const PackedPrim& p, const RayQuery& q, Hit& hit) {
    float t;
    if (!gpu::hit_sphere(p.v0, p.v1.x, q.ray, hit.t, t) || !closer_hit(t, p.ref, hit)) return false;
    hit.t = t, hit.ref = p.ref;
    return true;
}

inline bool hit_prim(const PackedPrim& p, const RayQuery& q, Hit& hit) {
    return (p.ref & gpu::REF_SPHERE_BIT) ? hit_sphere(p, q, hit) : hit_triangle(p, q, hit);
}

}  // namespace bvhlab
