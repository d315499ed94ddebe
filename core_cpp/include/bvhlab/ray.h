// ray.h — rays, hits, and the ray-box / ray-primitive tests the CPU traversal uses.
#pragma once
#include <cmath>
#include <cstdint>
#include <limits>
#include "bvhlab/geometry.h"
#include "gpu_types.h"

namespace bvhlab {

inline constexpr float kInfinity = std::numeric_limits<float>::infinity();
inline constexpr std::uint32_t kNoHit = 0xffffffffu;

/// A ray: points origin + t·dir for t in (tmin, tmax). dir need not be normalised.
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

/// A ray with what the box test needs precomputed.
struct RayQuery {
    Vec3 origin, dir, inv_dir;
    float tmin, tmax;

    /// inv_dir is the exact IEEE inverse: ±inf for a zero component (see hit_box for why that is safe).
    explicit RayQuery(const Ray& r)
        : origin(r.origin), dir(r.dir), inv_dir{1.0f / r.dir.x, 1.0f / r.dir.y, 1.0f / r.dir.z},
          tmin(r.tmin), tmax(r.tmax) {}
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
inline bool hit_box(const gpu::BvhNode& n, const RayQuery& q, float tmax, float& t_enter) {
    const bool nx = std::signbit(q.inv_dir.x), ny = std::signbit(q.inv_dir.y), nz = std::signbit(q.inv_dir.z);
    const float near_x = ((nx ? n.hi.x : n.lo.x) - q.origin.x) * q.inv_dir.x;
    const float near_y = ((ny ? n.hi.y : n.lo.y) - q.origin.y) * q.inv_dir.y;
    const float near_z = ((nz ? n.hi.z : n.lo.z) - q.origin.z) * q.inv_dir.z;
    const float far_x = ((nx ? n.lo.x : n.hi.x) - q.origin.x) * q.inv_dir.x;
    const float far_y = ((ny ? n.lo.y : n.hi.y) - q.origin.y) * q.inv_dir.y;
    const float far_z = ((nz ? n.lo.z : n.hi.z) - q.origin.z) * q.inv_dir.z;
    const float t0 = raise_to(raise_to(raise_to(q.tmin, near_x), near_y), near_z);
    const float t1 = lower_to(lower_to(lower_to(tmax, far_x), far_y), far_z);
    t_enter = t0;
    return t0 <= t1;
}

/// The closest-hit rule of every traversal, CPU and GPU (one rule, so that the three traversals
/// and the tracer agree when distances tie): a candidate at distance t in (tmin, tmax) replaces
/// the current hit when it is nearer, or as near and of a smaller primitive reference
/// (triangles before spheres, then the lower index).
inline bool closer_hit(float t, std::uint32_t ref, const Hit& hit) {
    return t < hit.t || (t == hit.t && hit.ref != kNoHit && ref < hit.ref);
}

/// Möller–Trumbore on a packed triangle; updates `hit` when closer_hit() says so.
inline bool hit_triangle(const PackedPrim& p, const RayQuery& q, Hit& hit) {
    Vec3 e1{p.e1[0], p.e1[1], p.e1[2]}, e2{p.e2[0], p.e2[1], p.e2[2]};
    Vec3 pvec = cross(q.dir, e2);
    float det = dot(e1, pvec);
    if (det == 0.0f) return false;  // parallel, or a degenerate triangle (packed with zero edges)
    float inv_det = 1.0f / det;
    Vec3 tvec = q.origin - Vec3{p.p[0], p.p[1], p.p[2]};
    float u = dot(tvec, pvec) * inv_det;
    if (!(u >= 0.0f && u <= 1.0f)) return false;
    Vec3 qvec = cross(tvec, e1);
    float v = dot(q.dir, qvec) * inv_det;
    if (!(v >= 0.0f && u + v <= 1.0f)) return false;
    float t = dot(e2, qvec) * inv_det;
    if (!(t > q.tmin && closer_hit(t, p.ref, hit))) return false;
    hit.t = t, hit.ref = p.ref, hit.u = u, hit.v = v;
    return true;
}

/// Nearest root of |o + t·d - c|² = r² in (tmin, hit.t); u, v are filled in by finish_hit().
inline bool hit_sphere(const PackedPrim& p, const RayQuery& q, Hit& hit) {
    Vec3 oc = q.origin - Vec3{p.p[0], p.p[1], p.p[2]};
    float r = p.e1[0];
    float a = dot(q.dir, q.dir), b = dot(oc, q.dir), c = dot(oc, oc) - r * r;
    float disc = b * b - a * c;
    if (!(disc >= 0.0f)) return false;
    float s = std::sqrt(disc);
    float t = (-b - s) / a;
    if (!(t > q.tmin)) t = (-b + s) / a;
    if (!(t > q.tmin && closer_hit(t, p.ref, hit))) return false;
    hit.t = t, hit.ref = p.ref;
    return true;
}

inline bool hit_prim(const PackedPrim& p, const RayQuery& q, Hit& hit) {
    return (p.ref & gpu::REF_SPHERE_BIT) ? hit_sphere(p, q, hit) : hit_triangle(p, q, hit);
}

}  // namespace bvhlab
