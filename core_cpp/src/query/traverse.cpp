#include "bvhlab/traverse.h"

#include <stdexcept>

#include "bvhlab/cancel.h"
#include "bvhlab/ray_record.h"
#include "bvhlab/coordinate_range.h"
#include "bvhlab/wide_bvh.h"

#include <algorithm>
#include <numbers>

#include "bvhlab/thread_pool.h"

namespace bvhlab {
namespace {

/// What intersect() reports of its steps: nothing (every query but the inspector's record; it
/// compiles to the code it was before), or each test into a TraversalRecord (ray_record.h).
struct NoRecord {
    void box(std::uint32_t, bool) {}
    void prim(std::uint32_t, std::uint32_t, bool) {}
};
struct Recorder {
    TraversalRecord& r;
    void box(std::uint32_t node, bool hit) { r.box_nodes.push_back(node), r.box_hit.push_back(hit); }
    void prim(std::uint32_t leaf, std::uint32_t slot, bool closer) {
        r.prim_slots.push_back(slot), r.prim_leaf.push_back(leaf), r.prim_closer.push_back(closer);
        r.prim_box_test.push_back(std::uint32_t(r.box_nodes.size()));
        if (closer) r.hit_leaf = leaf;
    }
};

template <class Record>
void test_leaf(const Bvh& bvh, std::uint32_t i, const RayQuery& q, Hit& hit, Record& record) {
    const BvhNode& n = bvh.nodes[i];
    for (std::uint32_t k = n.index, end = n.index + leaf_count(n); k < end; ++k) {
        const bool closer = hit_prim(bvh.prims[k], q, hit);
        if (closer) hit.slot = k;
        record.prim(i, k, closer);
    }
}

/// Ordered depth-first traversal: test both children's boxes, descend into the nearer, push the
/// farther with its entry distance so it is dropped if a closer hit is found meanwhile.
template <class Record>
std::uint32_t traverse_stack(const Bvh& bvh, const RayQuery& q, Hit& hit, Record& record) {
    struct Entry {
        std::uint32_t node;
        float t;
    };
    Entry stack[gpu::MAX_TREE_HEIGHT];
    std::uint32_t sp = 0, visited = 1, i = 0;
    const BvhNode* nodes = bvh.nodes.data();
    float t_root;
    const bool hit_root = hit_box(nodes[0], q, hit.t, t_root);
    record.box(0, hit_root);
    if (!hit_root) return visited;
    for (;;) {
        const BvhNode& n = nodes[i];
        if (is_leaf(n)) {
            test_leaf(bvh, i, q, hit, record);
        } else {
            std::uint32_t a = i + 1, b = n.index;
            float ta, tb;
            bool hit_a = hit_box(nodes[a], q, hit.t, ta), hit_b = hit_box(nodes[b], q, hit.t, tb);
            visited += 2;
            record.box(a, hit_a), record.box(b, hit_b);
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
template <class Record>
std::uint32_t traverse_stackless(const Bvh& bvh, const RayQuery& q, Hit& hit, Record& record) {
    const BvhNode* nodes = bvh.nodes.data();
    const std::uint32_t count = bvh.node_count();
    std::uint32_t visited = 0;
    for (std::uint32_t i = 0; i < count;) {
        const BvhNode& n = nodes[i];
        float t;
        ++visited;
        const bool entered = hit_box(n, q, hit.t, t);
        record.box(i, entered);
        if (!entered) {
            i = skip_index(n, i);
            continue;
        }
        if (is_leaf(n)) test_leaf(bvh, i, q, hit, record);
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

namespace {
template <class Record>
Hit intersect_with(const Bvh& bvh, const Ray& ray, Traversal mode, std::uint32_t* nodes_visited, Record& record) {
    Hit hit;
    hit.t = ray.tmax;
    std::uint32_t visited = 0;
    if (!bvh.empty()) {
        RayQuery q(ray);
        if (mode == Traversal::Wide) throw std::invalid_argument("use intersect_wide for Traversal::Wide");
        visited =
            mode == Traversal::Stack ? traverse_stack(bvh, q, hit, record) : traverse_stackless(bvh, q, hit, record);
    }
    if (hit.ref == kNoHit) hit.t = kInfinity;
    finish_hit(bvh, ray, hit);
    if (nodes_visited) *nodes_visited = visited;
    return hit;
}
}  // namespace

Hit intersect(const Bvh& bvh, const Ray& ray, Traversal mode, std::uint32_t* nodes_visited) {
    NoRecord none;
    return intersect_with(bvh, ray, mode, nodes_visited, none);
}

Hit detail::intersect_recorded(const Bvh& bvh, const Ray& ray, Traversal mode, TraversalRecord& record) {
    Recorder recorder{record};
    return intersect_with(bvh, ray, mode, nullptr, recorder);
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
