#include "bvhlab/traverse.h"

#include <stdexcept>

#include "bvhlab/cancel.h"
#include "bvhlab/coordinate_range.h"
#include "bvhlab/wide_bvh.h"

#include <algorithm>
#include <numbers>

#include "bvhlab/thread_pool.h"

namespace bvhlab {
namespace {

void test_leaf(const Bvh& bvh, const BvhNode& n, const RayQuery& q, Hit& hit) {
    for (std::uint32_t k = n.index, end = n.index + leaf_count(n); k < end; ++k)
        if (hit_prim(bvh.prims[k], q, hit)) hit.slot = k;
}

/// Ordered depth-first traversal: test both children's boxes, descend into the nearer, push the
/// farther with its entry distance so it is dropped if a closer hit is found meanwhile.
std::uint32_t traverse_stack(const Bvh& bvh, const RayQuery& q, Hit& hit) {
    struct Entry {
        std::uint32_t node;
        float t;
    };
    Entry stack[gpu::MAX_TREE_HEIGHT];
    std::uint32_t sp = 0, visited = 1, i = 0;
    const BvhNode* nodes = bvh.nodes.data();
    float t_root;
    if (!hit_box(nodes[0], q, hit.t, t_root)) return visited;
    for (;;) {
        const BvhNode& n = nodes[i];
        if (is_leaf(n)) {
            test_leaf(bvh, n, q, hit);
        } else {
            std::uint32_t a = i + 1, b = n.index;
            float ta, tb;
            bool hit_a = hit_box(nodes[a], q, hit.t, ta), hit_b = hit_box(nodes[b], q, hit.t, tb);
            visited += 2;
            if (hit_a && hit_b) {
                if (tb < ta) std::swap(a, b), std::swap(ta, tb);
                stack[sp++] = {b, tb};
                i = a;
                continue;
            }
            if (hit_a || hit_b) {
                i = hit_a ? a : b;
                continue;
            }
        }
        do {  // pop, skipping entries farther than the closest hit so far
            if (sp == 0) return visited;
            --sp;
        } while (!may_hold_closer(stack[sp].t, hit.t));
        i = stack[sp].node;
    }
}

/// Stackless traversal (report §3.1): nodes in depth-first order; a missed box jumps to its skip
/// index, the first node after its subtree.
std::uint32_t traverse_stackless(const Bvh& bvh, const RayQuery& q, Hit& hit) {
    const BvhNode* nodes = bvh.nodes.data();
    const std::uint32_t count = bvh.node_count();
    std::uint32_t visited = 0;
    for (std::uint32_t i = 0; i < count;) {
        const BvhNode& n = nodes[i];
        float t;
        ++visited;
        if (!hit_box(n, q, hit.t, t)) {
            i = skip_index(n, i);
            continue;
        }
        if (is_leaf(n)) test_leaf(bvh, n, q, hit);
        ++i;
    }
    return visited;
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
            Ray ray{{o[0], o[1], o[2]}, {d[0], d[1], d[2]}, rays.tmin, rays.tmax};
            const float t_scale = scale_ray(ray);  // exact; keeps the arithmetic in range
            std::uint32_t visited;
            Hit h = mode == Traversal::Wide ? intersect_wide(*wide, bvh, ray, &visited)
                                            : intersect(bvh, ray, mode, &visited);
            bool miss = h.ref == kNoHit;
            out.t[i] = h.t * t_scale;  // inf stays inf
            out.prim[i] = miss ? -1 : std::int32_t(h.ref & gpu::REF_INDEX_MASK);
            if (out.kind) out.kind[i] = miss ? 0 : std::uint8_t((h.ref & gpu::REF_SPHERE_BIT) ? 1 : 0);
            if (out.u) out.u[i] = h.u;
            if (out.v) out.v[i] = h.v;
            if (out.nodes_visited) out.nodes_visited[i] = visited;
        }
    };
    ThreadPool::shared().run((rays.count + kChunk - 1) / kChunk, threads, chunk, [&] {
        if (cancel) cancel->poll();
    });
    if (cancel && cancel->stop_requested()) throw Cancelled();
}

}  // namespace bvhlab
