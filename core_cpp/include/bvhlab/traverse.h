// traverse.h — closest-hit queries on the CPU, with a stack and stackless (report §2.2, §3.1).
#pragma once
#include <cstdint>
#include "bvhlab/bvh.h"
#include "bvhlab/ray.h"

namespace bvhlab {

enum class Traversal {
    Stack,      ///< depth-first, nearer child first, a fixed stack of MAX_TREE_HEIGHT entries
    Stackless,  ///< depth-first in node order, following skip indices on a miss (report §3.1)
    Wide,       ///< the 4-wide conversion (wide_bvh.h), nearer children first: the fastest on CPUs
};

struct WideBvh;

/// Closest hit of one ray; `nodes_visited` (if given) counts the box tests.
Hit intersect(const Bvh& bvh, const Ray& ray, Traversal mode, std::uint32_t* nodes_visited = nullptr);

/// Rays and results as flat arrays (numpy layout). Output pointers other than t and ref may be null.
struct RayBatch {
    const float* origins = nullptr;     ///< N×3
    const float* directions = nullptr;  ///< N×3
    std::size_t count = 0;
    float tmin = 0.0f, tmax = kInfinity;
};
struct HitBatch {
    float* t = nullptr;                ///< inf on a miss
    std::int32_t* prim = nullptr;      ///< index within its kind; -1 on a miss
    std::uint8_t* kind = nullptr;      ///< 0 triangle, 1 sphere (0 on a miss)
    float* u = nullptr;
    float* v = nullptr;
    std::uint32_t* nodes_visited = nullptr;
};

/// Closest hits of a batch, spread over `threads` threads (0 = all). Results do not depend on it.
/// Traversal::Wide needs `wide` (make_wide(bvh)).
void intersect_batch(const Bvh& bvh, const RayBatch& rays, const HitBatch& hits, Traversal mode,
                     std::uint32_t threads = 0, const WideBvh* wide = nullptr);

/// Sphere u, v from the hit point (done once per ray, not per candidate).
void finish_hit(const Bvh& bvh, const Ray& ray, Hit& hit);

}  // namespace bvhlab
