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

    explicit RayQuery(const Ray& r) : origin(r.origin), dir(r.dir), tmin(r.tmin), tmax(r.tmax) {
        // A zero component would give 0·inf = NaN on a slab plane; a huge finite inverse is exact enough.
        auto inv = [](float d) { return 1.0f / (std::fabs(d) < 1e-30f ? std::copysign(1e-30f, d) : d); };
        inv_dir = {inv(dir.x), inv(dir.y), inv(dir.z)};
    }
};

/// Slab test; on a hit, `t_enter` is where the ray enters the box (clamped to tmin).
inline bool hit_box(const gpu::BvhNode& n, const RayQuery& q, float tmax, float& t_enter) {
    float tx0 = (n.lo.x - q.origin.x) * q.inv_dir.x, tx1 = (n.hi.x - q.origin.x) * q.inv_dir.x;
    float ty0 = (n.lo.y - q.origin.y) * q.inv_dir.y, ty1 = (n.hi.y - q.origin.y) * q.inv_dir.y;
    float tz0 = (n.lo.z - q.origin.z) * q.inv_dir.z, tz1 = (n.hi.z - q.origin.z) * q.inv_dir.z;
    float t0 = std::max(std::max(std::min(tx0, tx1), std::min(ty0, ty1)), std::max(std::min(tz0, tz1), q.tmin));
    float t1 = std::min(std::min(std::max(tx0, tx1), std::max(ty0, ty1)), std::min(std::max(tz0, tz1), tmax));
    t_enter = t0;
    return t0 <= t1;
}

/// Möller–Trumbore on a packed triangle; updates `hit` when closer than hit.t.
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
    if (!(t > q.tmin && t < hit.t)) return false;
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
    if (!(t > q.tmin && t < hit.t)) return false;
    hit.t = t, hit.ref = p.ref;
    return true;
}

inline bool hit_prim(const PackedPrim& p, const RayQuery& q, Hit& hit) {
    return (p.ref & gpu::REF_SPHERE_BIT) ? hit_sphere(p, q, hit) : hit_triangle(p, q, hit);
}

}  // namespace bvhlab
