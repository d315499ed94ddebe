// ray_batch.h — the loop of every batch query (intersect_batch, occluded_batch and their two-level
// versions): rays checked, cut into chunks on the shared pool, each ray scaled for the arithmetic
// (coordinate_range.h), Ctrl-C honoured between chunks.
#pragma once
#include <algorithm>
#include <cstddef>
#include <type_traits>

#include "bvhlab/cancel.h"
#include "bvhlab/coordinate_range.h"
#include "bvhlab/thread_pool.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"

namespace bvhlab {

/// Rays a task of a batch query takes (one call of for_each_chunk's chunk).
inline constexpr std::size_t kRayChunk = kWideBatch;

/// Room for N objects of a trivial type T (Ray, Hit), left unwritten: a chunk's arrays of T
/// (whose members have default values) cost a pass of stores when declared as T[N] (Sponza
/// random rays: 33 instructions a ray), and every element is written before it is read.
template <class T, std::size_t N>
struct Scratch {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);
    alignas(T) std::byte bytes[N * sizeof(T)];
    T* data() { return reinterpret_cast<T*>(bytes); }
    T& operator[](std::size_t i) { return data()[i]; }
};

/// Calls `chunk(begin, end)` for the batch's chunks of kRayChunk rays, spread over the shared pool,
/// with the checks and cancellation of every batch query.
template <class Chunk>
void for_each_chunk(const RayBatch& rays, std::uint32_t threads, Cancellation* cancel, Chunk&& chunk) {
    check_rays(rays);
    if (cancel && cancel->poll()) throw Cancelled();  // asked to stop before anything started
    auto task = [&](std::size_t k, unsigned slot) {
        // the calling thread (slot 0) runs the check; the others read the flag
        if (cancel && (slot == 0 ? cancel->poll() : cancel->stop_requested())) return;
        chunk(k * kRayChunk, std::min(rays.count, (k + 1) * kRayChunk));
    };
    ThreadPool::shared().run((rays.count + kRayChunk - 1) / kRayChunk, threads, task, [&] {
        if (cancel) cancel->poll();
    });
    if (cancel && cancel->stop_requested()) throw Cancelled();
}

/// Ray i of the batch (with its own tmax where the batch has one per ray), scaled by scale_ray,
/// whose factor goes to `t_scale`: a t of the scaled ray times t_scale is one in the caller's units.
inline Ray scaled_ray(const RayBatch& rays, std::size_t i, float& t_scale) {
    const float* o = rays.origins + 3 * i;
    const float* d = rays.directions + 3 * i;
    Ray ray{{o[0], o[1], o[2]}, {d[0], d[1], d[2]}, rays.tmin, rays.tmax_of ? rays.tmax_of[i] : rays.tmax};
    t_scale = scale_ray(ray);  // exact; keeps the arithmetic in range
    return ray;
}

/// Calls `visit(i, ray, t_scale)` for every ray of the batch (scaled_ray).
template <class Visit>
void for_each_ray(const RayBatch& rays, std::uint32_t threads, Cancellation* cancel, Visit&& visit) {
    for_each_chunk(rays, threads, cancel, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            float t_scale;
            const Ray ray = scaled_ray(rays, i, t_scale);
            visit(i, ray, t_scale);
        }
    });
}

/// Calls `visit(begin, n, rays, t_scale)` for each chunk of the batch: its rays begin .. begin + n
/// as rays[0, n) (scaled_ray) with their factors t_scale[0, n), for the queries that trace a
/// chunk at once (the wide tree's, intersect_wide_batch).
template <class Visit>
void for_each_ray_chunk(const RayBatch& rays, std::uint32_t threads, Cancellation* cancel, Visit&& visit) {
    for_each_chunk(rays, threads, cancel, [&](std::size_t begin, std::size_t end) {
        Scratch<Ray, kRayChunk> chunk;
        float t_scale[kRayChunk];
        for (std::size_t i = begin; i < end; ++i) chunk[i - begin] = scaled_ray(rays, i, t_scale[i - begin]);
        visit(begin, end - begin, static_cast<const Ray*>(chunk.data()), static_cast<const float*>(t_scale));
    });
}

/// hits[0, n) of rays begin .. begin + n (t in the scaled units of t_scale) to `out`, t back in the
/// caller's units.
inline void write_hits(const HitBatch& out, std::size_t begin, std::size_t n, const Hit* hits,
                       const std::uint32_t* visited, const float* t_scale) {
    for (std::size_t j = 0; j < n; ++j) {
        const std::size_t i = begin + j;
        const Hit& h = hits[j];
        const bool miss = h.ref == kNoHit;
        out.t[i] = h.t * t_scale[j];  // inf stays inf
        out.prim[i] = miss ? -1 : std::int32_t(h.ref & gpu::REF_INDEX_MASK);
        if (out.kind) out.kind[i] = miss ? 0 : std::uint8_t((h.ref & gpu::REF_SPHERE_BIT) ? 1 : 0);
        if (out.u) out.u[i] = h.u;
        if (out.v) out.v[i] = h.v;
        if (out.nodes_visited) out.nodes_visited[i] = visited[j];
    }
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
        write_hits(out, i, 1, &h, &visited, &t_scale);
    });
}

}  // namespace bvhlab
