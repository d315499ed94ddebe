// The rays of a benchmark through an Embree 3 scene, one rtcIntersect1 / rtcOccluded1 a ray: the
// query loops of both Embree peers (peer_embree.cpp, one triangle scene; tlas_embree.cpp, its
// two-level scene), so both time the same per-ray work.
#pragma once

#include <cstdint>
#include <limits>

#include <embree3/rtcore.h>

#include "bench_data.h"

namespace bench {

/// Closest hits: t (infinity on a miss) and the primitive (~0u on a miss) of each ray.
inline void embree_trace(RTCScene scene, const Rays& rays, float* t, std::uint32_t* prim) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (std::size_t i = 0; i < rays.count(); ++i) {
        const float* r = rays.od.data() + 6 * i;
        RTCRayHit rh{};
        rh.ray.org_x = r[0], rh.ray.org_y = r[1], rh.ray.org_z = r[2];
        rh.ray.dir_x = r[3], rh.ray.dir_y = r[4], rh.ray.dir_z = r[5];
        rh.ray.tnear = 0.0f, rh.ray.tfar = std::numeric_limits<float>::infinity();
        rh.ray.mask = ~0u;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &context, &rh);
        const bool miss = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID;
        t[i] = miss ? std::numeric_limits<float>::infinity() : rh.ray.tfar;
        prim[i] = miss ? ~0u : rh.hit.primID;
    }
}

/// Shadow rays: whether anything lies before each ray's tmax.
inline void embree_occluded(RTCScene scene, const Rays& rays, std::uint8_t* out) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (std::size_t i = 0; i < rays.count(); ++i) {
        const float* r = rays.od.data() + 6 * i;
        RTCRay ray{};
        ray.org_x = r[0], ray.org_y = r[1], ray.org_z = r[2];
        ray.dir_x = r[3], ray.dir_y = r[4], ray.dir_z = r[5];
        ray.tnear = 0.0f, ray.tfar = rays.tmax[i];
        ray.mask = ~0u;
        rtcOccluded1(scene, &context, &ray);
        out[i] = ray.tfar == -std::numeric_limits<float>::infinity();  // Embree's mark of a hit
    }
}

}  // namespace bench
