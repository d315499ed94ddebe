#include "bvhlab/traverse.h"

#include <algorithm>
#include <numbers>
#include <stdexcept>

#include "bvhlab/wide_bvh.h"
#include "ray_batch.h"
#include "walk.h"

namespace bvhlab {
namespace {

void test_leaf(const Bvh& bvh, const BvhNode& n, const RayQuery& q, Hit& hit) {
    for (std::uint32_t k = n.index, end = n.index + leaf_count(n); k < end; ++k)
        if (hit_prim(bvh.prims[k], q, hit)) hit.slot = k;
}

std::uint32_t traverse_stack(const Bvh& bvh, const RayQuery& q, Hit& hit) {
    return walk::stack(bvh.nodes.data(), q, hit.t, [&](const BvhNode& n) { test_leaf(bvh, n, q, hit); });
}

std::uint32_t traverse_stackless(const Bvh& bvh, const RayQuery& q, Hit& hit) {
    return walk::stackless(bvh.nodes.data(), bvh.node_count(), q, hit.t,
                           [&](const BvhNode& n) { test_leaf(bvh, n, q, hit); });
}

}  // namespace

void finish_hit(const Bvh& bvh, const Ray& ray, Hit& hit) {
    if (hit.ref == kNoHit || !(hit.ref & gpu::REF_SPHERE_BIT)) return;
    const PackedPrim& p = bvh.prims[hit.slot];
    Vec3 n = normalize(ray.origin + ray.dir * hit.t - Vec3{p.v0.x, p.v0.y, p.v0.z});
    hit.u = std::atan2(n.y, n.x) * float(0.5 / std::numbers::pi) + 0.5f;
    hit.v = std::acos(std::clamp(n.z, -1.0f, 1.0f)) * float(1.0 / std::numbers::pi);
}

Hit intersect(const Bvh& bvh, const Ray& ray, Traversal mode, std::uint32_t* nodes_visited) {
    Hit hit;
    hit.t = ray.tmax;
    std::uint32_t visited = 0;
    if (!bvh.empty()) {
        RayQuery q(ray);
        if (mode == Traversal::Wide) throw std::invalid_argument("use intersect_wide for Traversal::Wide");
        visited = mode == Traversal::Stack ? traverse_stack(bvh, q, hit) : traverse_stackless(bvh, q, hit);
    }
    if (hit.ref == kNoHit) hit.t = kInfinity;
    finish_hit(bvh, ray, hit);
    if (nodes_visited) *nodes_visited = visited;
    return hit;
}

void intersect_batch(const Bvh& bvh, const RayBatch& rays, const HitBatch& out, Traversal mode, std::uint32_t threads,
                     const WideBvh* wide, Cancellation* cancel) {
    if (mode == Traversal::Wide && !wide) throw std::invalid_argument("Traversal::Wide needs the wide tree");
    run_ray_batch(rays, out, threads, cancel, [&](std::size_t, const Ray& ray, std::uint32_t& visited) {
        return mode == Traversal::Wide ? intersect_wide(*wide, bvh, ray, &visited)
                                       : intersect(bvh, ray, mode, &visited);
    });
}

}  // namespace bvhlab
