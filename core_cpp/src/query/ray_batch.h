// ray_batch.h — the loop of every batch query (intersect_batch, occluded_batch and their two-level
// versions): rays checked, cut into chunks on the shared pool, each ray scaled for the arithmetic
// (coordinate_range.h), Ctrl-C honoured between chunks.
#pragma once
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

#include "bvhlab/cancel.h"
#include "bvhlab/coordinate_range.h"
#include "bvhlab/thread_pool.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"
#include "ray_order.h"
#include "wide_kernel.h"

namespace bvhlab {

/// Rays a task of a batch query takes (one call of for_each_unchecked_chunk's chunk): four of the wide
/// walks' pieces (kWideBatch).
inline constexpr std::size_t kRayChunk = 4 * kWideBatch;

/// Room for N objects of a trivial type T (Ray, Hit), left unwritten: a chunk's arrays of T
/// (whose members have default values) cost a pass of stores when declared as T[N] (Sponza
/// random rays: 33 instructions a ray), and every element is written before it is read.
template <class T, std::size_t N>
struct Scratch {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);
    alignas(T) std::byte bytes[N * sizeof(T)];
    T* data() { return reinterpret_cast<T*>(bytes); }
    const T* data() const { return reinterpret_cast<const T*>(bytes); }
    T& operator[](std::size_t i) { return data()[i]; }
    const T& operator[](std::size_t i) const { return data()[i]; }
};

/// Rays a per-ray walk (for_each_ray) traces between two looks at its ChunkStop: a chunk of
/// kRayChunk costly rays took seconds to see a Ctrl-C (the stack walk over 200,000 overlapping
/// triangles, ~3 ms a ray: 3.4 s; helper probe), and a look costs the caller's thread a clock read.
inline constexpr std::size_t kRaysBetweenStops = 16;

/// Whether a chunk's work should end early: the calling thread (slot 0) runs the cancellation's
/// poll, the others read its flag (for the long chunks of costly rays; the batch throws Cancelled
/// after its chunks have ended, as when it stops between them).
struct ChunkStop {
    Cancellation* cancel;
    bool caller;
    bool operator()() const { return cancel && (caller ? cancel->poll() : cancel->stop_requested()); }
};

/// Calls `chunk(begin, end, stop)` for the batch's chunks of kRayChunk rays, spread over the shared
/// pool, with the cancellation of every batch query (`stop`, a ChunkStop, for a look inside a
/// chunk) but no check of the rays (for_each_ray checks them first; for_each_ray_piece as it
/// reads them).
template <class Chunk>
void for_each_unchecked_chunk(const RayBatch& rays, std::uint32_t threads, Cancellation* cancel, Chunk&& chunk) {
    if (cancel && cancel->poll()) throw Cancelled();  // asked to stop before anything started
    auto task = [&](std::size_t k, unsigned slot) {
        const ChunkStop stop{cancel, slot == 0};
        if (stop()) return;
        chunk(k * kRayChunk, std::min(rays.count, (k + 1) * kRayChunk), stop);
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

/// Calls `visit(i, ray, t_scale)` for every ray of the batch (scaled_ray), the rays checked first
/// (check_rays) unless `checked` says the caller has (a reordered copy, whose refused ray would be
/// named by its place in the copy).
template <class Visit>
void for_each_ray(const RayBatch& rays, std::uint32_t threads, Cancellation* cancel, Visit&& visit,
                  bool checked = false) {
    if (!checked) check_rays(rays);
    for_each_unchecked_chunk(rays, threads, cancel, [&](std::size_t begin, std::size_t end, const ChunkStop& stop) {
        for (std::size_t i = begin; i < end; ++i) {
            if (i != begin && (i - begin) % kRaysBetweenStops == 0 && stop()) return;
            float t_scale;
            const Ray ray = scaled_ray(rays, i, t_scale);
            visit(i, ray, t_scale);
        }
    });
}

/// The bits of |x| as an unsigned integer, which orders as |x| does for numbers, above every
/// number (and infinity) for a NaN.
inline std::uint32_t magnitude_bits(float x) {
    std::uint32_t b;
    std::memcpy(&b, &x, sizeof b);
    return b & 0x7fffffffu;
}

/// A piece of a batch as the wide tree's batch walks take it (wide_kernel.h intersect_wide_grouped):
/// its rays scaled (scaled_ray), each with its factor, and grouped by octant (order_by_octant).
/// 10 KiB: made on the heap (make_piece), not on the calling thread's stack, which a batch query
/// keeps small (design.md, "Threading model": a thread of 32 KiB runs every batch query).
struct RayPiece {
    Scratch<Ray, kWideBatch> rays;
    float t_scale[kWideBatch];
    std::uint32_t order[kWideBatch], start[9];
    std::uint32_t count;
};

/// A RayPiece on the heap, left unwritten (prepare_piece writes what is read).
inline std::unique_ptr<RayPiece> make_piece() { return std::unique_ptr<RayPiece>(new RayPiece); }

/// prepare_piece's pass (below) over the caller's rays [0, n − n mod 8), eight at a time, where
/// the active instruction set has a vector pass (AVX2: ray_piece_avx2.cpp; ray_piece.cpp picks),
/// else none: each ray's origin and direction from origins and directions (3 floats a ray), its
/// tmax from tmax_of[i] (or `tmax` where null); the checks or-ed into `refused`, the scaled rays,
/// their factors and their octants written as the scalar pass writes them. Returns the rays done.
std::uint32_t prepare_rays_vector(const float* origins, const float* directions, const float* tmax_of, float tmin,
                                  float tmax, std::uint32_t n, Ray* rays, float* t_scale, std::uint8_t* octant,
                                  std::uint32_t& refused);

/// Rays begin .. end (at most kWideBatch) of the batch to `piece`, in one pass over the caller's
/// arrays: each checked by check_rays' rules, scaled (scaled_ray) and given its octant (the sign
/// bits of its direction), then ordered by octant. Returns false where a ray is refused (the
/// piece is then not to be traced; check_rays names the ray).
/// The checks are in_coordinate_range and direction_in_range on the bits of |x|
/// (magnitude_bits): a NaN's exceed every number's, so one integer comparison a bound refuses
/// it, and the largest |component| is the largest of the bits.
/// `index` (kIndexed): the piece's rays are rays index[0, end - begin) of the batch rather than
/// begin .. end (for_each_block's probe). A contiguous piece's rays go eight at a time through the
/// vector pass where there is one (prepare_rays_vector; repeat1m's camera rays: 68 instructions a ray in
/// this function without it).
template <bool kIndexed = false>
inline bool prepare_piece(const RayBatch& rays, std::size_t begin, std::size_t end, RayPiece& piece,
                          const std::uint32_t* index = nullptr) {
    constexpr std::uint32_t kMaxOrigin = kMaxCoordinateBits, kLeast = kMinDirectionBits, kMost = kMaxDirectionBits;
    const auto n = std::uint32_t(end - begin);
    // the batch's fields in locals: the stores to the piece could alias them for the compiler
    const std::size_t first = kIndexed ? 0 : begin;
    const float *origins = rays.origins + 3 * first, *directions = rays.directions + 3 * first;
    const float* tmax_of = rays.tmax_of ? rays.tmax_of + first : nullptr;
    const float tmin = rays.tmin, tmax = rays.tmax;
    std::uint8_t octant[kWideBatch];
    std::uint32_t refused = 0;
    const auto bits = [](const float* p) {
        std::uint32_t b;
        std::memcpy(&b, p, sizeof b);
        return b;
    };
    std::uint32_t j = 0;
    if (!kIndexed)
        j = prepare_rays_vector(origins, directions, tmax_of, tmin, tmax, n, piece.rays.data(), piece.t_scale, octant,
                                refused);
    for (; j < n; ++j) {  // as bits: no float operation before the scaling
        const std::size_t i = kIndexed ? index[j] : j;
        const float *o = origins + 3 * i, *d = directions + 3 * i;
        const std::uint32_t dx = bits(d), dy = bits(d + 1), dz = bits(d + 2), m = 0x7fffffffu;
        const std::uint32_t dir = std::max(dx & m, std::max(dy & m, dz & m));
        const std::uint32_t origin = std::max(bits(o) & m, std::max(bits(o + 1) & m, bits(o + 2) & m));
        refused |= std::uint32_t(origin > kMaxOrigin) | std::uint32_t(dir - kLeast > kMost - kLeast);
        Ray& ray = piece.rays[j];
        ray.origin = Vec3{o[0], o[1], o[2]}, ray.dir = Vec3{d[0], d[1], d[2]};
        ray.tmin = tmin, ray.tmax = tmax_of ? tmax_of[i] : tmax;
        if (tmax_of) refused |= std::uint32_t(!(ray.tmax >= 0.0f));
        piece.t_scale[j] = scale_ray_by(ray, dir);  // any float where refused: the piece is not traced
        octant[j] = std::uint8_t(octant_of_bits(dx, dy, dz));
    }
    if (refused) return false;
    piece.count = n;
    order_by_octant(octant, n, piece.order, piece.start);
    return true;
}

/// Calls `visit(begin, piece)` for each piece of the batch (prepare_piece: rays begin ..
/// begin + piece.count, scaled and grouped by octant), for the queries that trace a piece at once
/// (the wide tree's). The rays are checked as they are read rather than in a pass before (which
/// read the caller's arrays twice: 44 instructions a ray, repeat1m primary rays); a piece with a
/// refused ray is not traced, the other threads stop, and check_rays throws naming the first
/// (the outputs are then left incomplete, as when cancelled).
template <class Visit>
void for_each_ray_piece(const RayBatch& rays, std::uint32_t threads, Cancellation* cancel, Visit&& visit) {
    std::atomic<bool> refused{false};
    for_each_unchecked_chunk(rays, threads, cancel, [&](std::size_t begin, std::size_t end, const ChunkStop& stop) {
        const std::unique_ptr<RayPiece> piece = make_piece();
        for (std::size_t at = begin; at < end && !refused.load(std::memory_order_relaxed); at += kWideBatch) {
            if (at != begin && stop()) return;
            if (!prepare_piece(rays, at, std::min(end, at + kWideBatch), *piece)) {
                refused.store(true, std::memory_order_relaxed);
                return;
            }
            visit(at, static_cast<const RayPiece&>(*piece));
        }
    });
    if (refused.load()) {
        check_rays(rays);  // throws, naming the first refused ray
        throw std::logic_error("a batch refused a ray that check_rays accepts");
    }
}

/// Rays [base, base + count) of a batch as a batch of their own.
inline RayBatch part_of(const RayBatch& rays, std::size_t base, std::size_t count) {
    RayBatch b = rays;
    b.count = count;
    b.origins += 3 * base, b.directions += 3 * base;
    if (b.tmax_of) b.tmax_of += base;
    return b;
}

/// A sample of kWideBatch of `part`'s rays for for_each_block's probe: evenly spread over the
/// whole part (its first rays may lie together: sorted otherwise), from its first ray to its
/// last, or (`between`) each halfway to the next. Throws, as check_rays does, where a ray is refused.
inline void probe_sample(const RayBatch& rays, const RayBatch& part, bool between, RayPiece& piece) {
    std::uint32_t sample[kWideBatch];
    for (std::uint32_t j = 0; j < kWideBatch; ++j)
        sample[j] = between ? std::uint32_t(std::uint64_t(2 * j + 1) * (part.count - 1) / (2 * kWideBatch))
                            : std::uint32_t(std::uint64_t(j) * (part.count - 1) / (kWideBatch - 1));
    if (!prepare_piece<true>(part, 0, kWideBatch, piece, sample)) {
        check_rays(rays);  // throws, naming the first refused ray
        throw std::logic_error("a batch refused a ray that check_rays accepts");
    }
}

/// The time (ns) a ray of `part` waits on memory (kOrderStallNs, ray_order.h): a sample of its
/// rays traced twice by `probe`, the first time with the caches as the rays traced before left
/// them, the second with the sample's own lines in them; the difference a ray.
template <class Probe>
double memory_stall_ns(const RayBatch& rays, const RayBatch& part, Probe& probe) {
    const std::unique_ptr<RayPiece> piece = make_piece();
    probe_sample(rays, part, true, *piece);
    using Clock = std::chrono::steady_clock;
    volatile double kept;  // the probe's answers kept: a probe without effects is still timed
    const auto start = Clock::now();
    kept = probe(static_cast<const RayPiece&>(*piece));
    const auto again = Clock::now();
    kept = probe(static_cast<const RayPiece&>(*piece));
    const std::chrono::duration<double, std::nano> cold = again - start, warm = Clock::now() - again;
    (void)kept;
    return (cold - warm).count() / kWideBatch;
}

/// The wide tree's batch queries, block by block (kOrderBlock rays): calls `trace(base, part,
/// sorted, walk)` for consecutive parts [base, base + part.count) of the batch, with `sorted` null
/// where the part is traced as it is, else the part's rays copied in ray order (ray_order.h: trace
/// then traces sorted->batch(part) and puts each result back at sorted->index), and `walk` how the
/// closest-hit walks take the rays that go alone (wide_bvh.h WideWalk). A block of at least
/// kOrderLeast rays that is not in ray order already (in_ray_order) is reordered
/// - whole, where a sample of its rays, spread evenly over it, visit at least kOrderNodes wide
///   nodes on average, which `probe(piece)` says (it traces a piece's rays without keeping any
///   result, each alone, and returns the wide nodes they visit on average); its rays then go
///   interleaved. Not with kByNodes false (the two-level walks, whose counts are not one tree's
///   wide nodes): their probe is only timed;
/// - else, in a block of at least kOrderTimedLeast rays, from its kOrderWarmRays-th ray on, where
///   its first kOrderWarmRays rays, traced as they are, leave the caches as the rest would find
///   them and a sample of the rest still waits on memory at least `stall_ns` a ray
///   (memory_stall_ns; detail::order_stall_ns, kOrderStallNs but where a test fixes the answer
///   with ±inf); the rest goes interleaved where the wait is at least detail::interleave_stall_ns
///   (kInterleaveStallNs).
/// Every other part goes alone. Throws, as check_rays does, where a ray of a sample is refused.
template <bool kByNodes = true, class Probe, class Trace>
void for_each_block(const RayBatch& rays, const Aabb& scene, Probe&& probe, Trace&& trace,
                    double stall_ns = detail::order_stall_ns.load(std::memory_order_relaxed),
                    double interleave_ns = detail::interleave_stall_ns.load(std::memory_order_relaxed)) {
    SortedRays sorted;
    for (std::size_t base = 0; base < rays.count || base == 0; base += kOrderBlock) {
        const RayBatch block = part_of(rays, base, std::min(kOrderBlock, rays.count - base));
        const RayKeys keys(scene, block.count);
        if (block.count < kOrderLeast || in_ray_order(block, keys)) {
            trace(base, block, nullptr, WideWalk::Alone);
            if (block.count == 0) break;
            continue;
        }
        bool costly = false;
        if constexpr (kByNodes) {
            const std::unique_ptr<RayPiece> piece = make_piece();
            probe_sample(rays, block, false, *piece);
            costly = probe(static_cast<const RayPiece&>(*piece)) >= kOrderNodes;
        }
        if (costly || block.count < kOrderTimedLeast) {
            if (costly) sort_rays(block, keys, sorted);
            trace(base, block, costly ? &sorted : nullptr, costly ? WideWalk::Interleaved : WideWalk::Alone);
            continue;
        }
        const std::size_t warm = kOrderWarmRays;
        trace(base, part_of(block, 0, warm), nullptr, WideWalk::Alone);
        const RayBatch rest = part_of(block, warm, block.count - warm);
        const double stall = memory_stall_ns(rays, rest, probe);
        const bool reorder = stall >= stall_ns;
        if (reorder) sort_rays(rest, keys, sorted);
        trace(base + warm, rest, reorder ? &sorted : nullptr,
              stall >= interleave_ns ? WideWalk::Interleaved : WideWalk::Alone);
    }
}

/// write_hits<true>'s work (below) on hits[0, n − n mod 8) (up to 256 of them) eight at a time, where the
/// active instruction set has a vector pass (AVX2: ray_piece_avx2.cpp), else none: each eight that
/// holds no sphere's hit written as write_hits writes it. Returns the eights written (bit g:
/// hits 8g .. 8g + 7), which the scalar loop then skips.
std::uint32_t write_hits_vector(const HitBatch& out, std::size_t begin, std::uint32_t n, const Hit* hits,
                                const std::uint32_t* visited, const float* t_scale);

/// hits[0, n) of rays begin .. begin + n (t in the scaled units of t_scale) to `out`, t back in the
/// caller's units. kFinish: the hits are as the wide walks leave them (intersect_wide_grouped: a
/// miss's t is the ray's tmax, a sphere's u, v not yet made), finished here (finish_hit with the
/// scaled rays[j]) rather than in a pass of their own; `visited` may then be null where `out` has
/// no nodes_visited.
template <bool kFinish = false>
void write_hits(const HitBatch& out, std::size_t begin, std::size_t n, Hit* hits, const std::uint32_t* visited,
                const float* t_scale, const Bvh* bvh = nullptr, const Ray* rays = nullptr) {
    // the outputs in locals: the stores could alias `out` for the compiler, which then reloaded it
    float *t = out.t + begin, *u = out.u ? out.u + begin : nullptr, *v = out.v ? out.v + begin : nullptr;
    std::int32_t* prim = out.prim + begin;
    std::uint8_t* kind = out.kind ? out.kind + begin : nullptr;
    std::uint32_t* nodes_visited = out.nodes_visited ? out.nodes_visited + begin : nullptr;
    // a piece's eights without a sphere's hit in one vector pass (kFinish: a piece of the wide batch)
    std::uint32_t written = 0;
    if constexpr (kFinish) written = write_hits_vector(out, begin, std::uint32_t(n), hits, visited, t_scale);
    for (std::size_t j = 0; j < n; ++j) {
        if (written >> (j / 8) & 1) {
            j += 7;
            continue;
        }
        Hit& h = hits[j];
        const bool miss = h.ref == kNoHit;
        if constexpr (kFinish)
            if (!miss && (h.ref & gpu::REF_SPHERE_BIT)) [[unlikely]]
                finish_hit(*bvh, rays[j], h);
        t[j] = kFinish && miss ? kInfinity : h.t * t_scale[j];  // inf stays inf
        prim[j] = miss ? -1 : std::int32_t(h.ref & gpu::REF_INDEX_MASK);
        if (kind) kind[j] = miss ? 0 : std::uint8_t((h.ref & gpu::REF_SPHERE_BIT) ? 1 : 0);
        if (u) u[j] = h.u;
        if (v) v[j] = h.v;
        if (nodes_visited) nodes_visited[j] = visited[j];
    }
}

/// Calls `trace(i, ray, visited)` for every ray of the batch (for_each_ray); `trace` returns the
/// ray's Hit (t in the scaled units) and its visited count, which are written to `out` (t back in
/// the caller's units); `checked` as for_each_ray's.
template <class Trace>
void run_ray_batch(const RayBatch& rays, const HitBatch& out, std::uint32_t threads, Cancellation* cancel,
                   Trace&& trace, bool checked = false) {
    for_each_ray(
        rays, threads, cancel,
        [&](std::size_t i, const Ray& ray, float t_scale) {
            std::uint32_t visited;
            Hit h = trace(i, ray, visited);
            write_hits(out, i, 1, &h, &visited, &t_scale);
        },
        checked);
}

}  // namespace bvhlab
