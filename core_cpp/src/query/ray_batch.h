// ray_batch.h — the loop of every batch query (intersect_batch, occluded_batch and their two-level
// versions): rays checked, cut into chunks on the shared pool, each ray scaled for the arithmetic
// (coordinate_range.h), Ctrl-C honoured between chunks.
#pragma once
#include <algorithm>

#include "bvhlab/cancel.h"
#include "bvhlab/coordinate_range.h"
#include "bvhlab/thread_pool.h"
#include "bvhlab/traverse.h"

namespace bvhlab {

/// Calls `visit(i, ray, t_scale)` for every ray of the batch, the ray (with its own tmax where the
/// batch has one per ray) already scaled by scale_ray, whose factor is `t_scale`: a t of the
/// scaled ray times t_scale is one in the caller's units.
template <class Visit>
void for_each_ray(const RayBatch& rays, std::uint32_t threads, Cancellation* cancel, Visit&& visit) {
    check_rays(rays);
    constexpr std::size_t kChunk = 1024;
    if (cancel && cancel->poll()) throw Cancelled();  // asked to stop before anything started
    auto chunk = [&](std::size_t k, unsigned slot) {
        // the calling thread (slot 0) runs the check; the others read the flag
        if (cancel && (slot == 0 ? cancel->poll() : cancel->stop_requested())) return;
        const std::size_t begin = k * kChunk, end = std::min(rays.count, begin + kChunk);
        for (std::size_t i = begin; i < end; ++i) {
            const float* o = rays.origins + 3 * i;
            const float* d = rays.directions + 3 * i;
            Ray ray{{o[0], o[1], o[2]}, {d[0], d[1], d[2]}, rays.tmin, rays.tmax_of ? rays.tmax_of[i] : rays.tmax};
            const float t_scale = scale_ray(ray);  // exact; keeps the arithmetic in range
            visit(i, ray, t_scale);
        }
    };
    ThreadPool::shared().run((rays.count + kChunk - 1) / kChunk, threads, chunk, [&] {
        if (cancel) cancel->poll();
    });
    if (cancel && cancel->stop_requested()) throw Cancelled();
}

/// Calls `trace(i, ray, visited)` for every ray of the batch (for_each_ray); `trace` returns the
/// ray's Hit (t in the scaled units) and its visited count, which are written to `out` (t back in
/// the caller's units).
template <class Trace>
void run_ray_batch(const RayBatch& rays, const HitBatch& out, std::uint32_t threads, Cancellation* cancel,
                   Trace&& trace) {
    for_each_ray(rays, threads, cancel, [&](std::size_t i, const Ray& ray, float t_scale) {
        std::uint32_t visited;
        const Hit h = trace(i, ray, visited);
        const bool miss = h.ref == kNoHit;
        out.t[i] = h.t * t_scale;  // inf stays inf
        out.prim[i] = miss ? -1 : std::int32_t(h.ref & gpu::REF_INDEX_MASK);
        if (out.kind) out.kind[i] = miss ? 0 : std::uint8_t((h.ref & gpu::REF_SPHERE_BIT) ? 1 : 0);
        if (out.u) out.u[i] = h.u;
        if (out.v) out.v[i] = h.v;
        if (out.nodes_visited) out.nodes_visited[i] = visited;
    });
}

}  // namespace bvhlab
