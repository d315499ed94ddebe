// traverse.h — closest-hit and any-hit (occluded) queries on the CPU, with a stack and stackless
// (report §2.2, §3.1).
#pragma once
#include <cstdint>
#include "bvhlab/bvh.h"
#include "bvhlab/ray.h"

namespace bvhlab {

enum class Traversal {
    Stack,      ///< depth-first, nearer child first, a fixed stack of MAX_TREE_HEIGHT entries
    Stackless,  ///< depth-first in node order, following skip indices on a miss (report §3.1)
    Wide,       ///< the 8-wide conversion (wide_bvh.h), nearer children first: the fastest on CPUs
};

struct WideBvh;
class Cancellation;

/// Closest hit of one ray; `nodes_visited` (if given) counts the box tests.
Hit intersect(const Bvh& bvh, const Ray& ray, Traversal mode, std::uint32_t* nodes_visited = nullptr);

/// Whether anything lies on the ray at t in (tmin, tmax): the any-hit query, which ends at the
/// first hit it finds. Exactly when intersect() would return a hit (its t < tmax), on every
/// traversal: the same walks, box tests and primitive tests (closer_hit against a hit at tmax).
bool occluded(const Bvh& bvh, const Ray& ray, Traversal mode);

/// Rays and results as flat arrays (numpy layout). Output pointers other than t and ref may be null.
struct RayBatch {
    const float* origins = nullptr;     ///< N×3
    const float* directions = nullptr;  ///< N×3
    std::size_t count = 0;
    float tmin = 0.0f, tmax = kInfinity;
    const float* tmax_of = nullptr;  ///< N: each ray's own tmax, in place of `tmax` when given
};
struct HitBatch {
    float* t = nullptr;            ///< inf on a miss
    std::int32_t* prim = nullptr;  ///< index within its kind; -1 on a miss
    std::uint8_t* kind = nullptr;  ///< 0 triangle, 1 sphere (0 on a miss)
    float* u = nullptr;
    float* v = nullptr;
    std::uint32_t* nodes_visited = nullptr;
};

/// Closest hits of a batch, spread over `threads` threads (0 = all). Results do not depend on it.
/// Traversal::Wide needs `wide` (make_wide(bvh)). Throws std::invalid_argument naming the first
/// ray whose origin lies outside ±kMaxCoordinate or whose direction's largest component lies
/// outside [kMinDirection, kMaxDirection] (coordinate_range.h), and a NaN or negative tmin or
/// scalar tmax (check_limits); each ray is scaled by a power of
/// two for the arithmetic (scale_ray), which changes no result but keeps it in range.
/// With `cancel`, the calling thread polls it between chunks of rays and inside them (every 16
/// rays, or piece of 256 on the wide tree), and every thread stops soon after a stop is
/// requested; then it throws Cancelled (the outputs are left incomplete).
void intersect_batch(const Bvh& bvh, const RayBatch& rays, const HitBatch& hits, Traversal mode,
                     std::uint32_t threads = 0, const WideBvh* wide = nullptr, Cancellation* cancel = nullptr);

/// Any-hit queries of a batch: occluded[i] = occluded(ray i), as intersect_batch's t[i] < tmax
/// (of ray i). Same rays, checks, threads and cancellation as intersect_batch; a NaN or negative
/// tmax (scalar or per ray) is refused too.
void occluded_batch(const Bvh& bvh, const RayBatch& rays, bool* occluded, Traversal mode, std::uint32_t threads = 0,
                    const WideBvh* wide = nullptr, Cancellation* cancel = nullptr);

/// Throws std::invalid_argument naming the first ray of `rays` that intersect_batch refuses (and
/// the first NaN or negative per-ray tmax, where the batch has them).
void check_rays(const RayBatch& rays);
/// Throws std::invalid_argument unless the batch's tmin and its scalar tmax are numbers ≥ 0 (with
/// per-ray tmax, check_rays checks those). A negative tmin is refused, not answered: ray.h Ray.
void check_limits(const RayBatch& rays);

/// Sphere u, v from the hit point (done once per ray, not per candidate).
void finish_hit(const Bvh& bvh, const Ray& ray, Hit& hit);

}  // namespace bvhlab
