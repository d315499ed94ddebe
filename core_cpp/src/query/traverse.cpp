#include "bvhlab/traverse.h"

#include <algorithm>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <utility>
#include <vector>

#include "bvhlab/ray_record.h"
#include "bvhlab/wide_bvh.h"
#include "ray_batch.h"
#include "walk.h"

namespace bvhlab {
namespace {

/// What intersect() reports of its steps: nothing (every query but the inspector's record; it
/// compiles to the code it was before), or each test into a TraversalRecord (ray_record.h).
struct NoRecord {
    static constexpr bool kHides = false;
    void box(std::uint32_t, bool) {}
    void prim(std::uint32_t, std::uint32_t, bool) {}
    bool hides(std::uint32_t) const { return false; }
};
struct Recorder {
    static constexpr bool kHides = true;
    TraversalRecord& r;
    const HiddenPrims& hidden;
    std::uint32_t mesh;
    bool hides(std::uint32_t ref) const { return hidden && hidden(mesh, ref); }
    void box(std::uint32_t node, bool hit) { r.box_nodes.push_back(node), r.box_hit.push_back(hit); }
    void prim(std::uint32_t leaf, std::uint32_t slot, bool closer) {
        r.prim_slots.push_back(slot), r.prim_leaf.push_back(leaf), r.prim_closer.push_back(closer);
        r.prim_box_test.push_back(std::uint32_t(r.box_nodes.size()));
        if (closer) r.hit_leaf = leaf;
    }
};

template <class Record>
void test_leaf(const Bvh& bvh, const BvhNode& n, const RayQuery& q, Hit& hit, Record& record) {
    const auto i = std::uint32_t(&n - bvh.nodes.data());
    for (std::uint32_t k = n.index, end = n.index + leaf_count(n); k < end; ++k) {
        if constexpr (Record::kHides) {  // a hidden primitive's hit is not taken (traverse.glsl visit_primitive)
            Hit tried = hit;
            const bool closer = hit_prim(bvh.prims[k], q, tried) && !record.hides(bvh.prims[k].ref);
            if (closer) hit = tried, hit.slot = k;
            record.prim(i, k, closer);
        } else {
            const bool closer = hit_prim(bvh.prims[k], q, hit);
            if (closer) hit.slot = k;
            record.prim(i, k, closer);
        }
    }
}

template <class Record>
std::uint32_t traverse_stack(const Bvh& bvh, const RayQuery& q, Hit& hit, Record& record) {
    return walk::stack(
        bvh.nodes.data(), q, hit.t, [&](const BvhNode& n) { test_leaf(bvh, n, q, hit, record); },
        [&](std::uint32_t node, bool entered) { record.box(node, entered); });
}

template <class Record>
std::uint32_t traverse_stackless(const Bvh& bvh, const RayQuery& q, Hit& hit, Record& record) {
    return walk::stackless(
        bvh.nodes.data(), bvh.node_count(), q, hit.t, [&](const BvhNode& n) { test_leaf(bvh, n, q, hit, record); },
        [&](std::uint32_t node, bool entered) { record.box(node, entered); });
}

/// The any-hit leaf (walk.h ends_walk): true at the first primitive hit at t in (tmin, tmax), by
/// the closest-hit test against a hit at tmax (closer_hit: nearer than tmax, as intersect's first
/// hit must be).
bool leaf_occludes(const Bvh& bvh, const BvhNode& n, const RayQuery& q, float tmax) {
    for (std::uint32_t k = n.index, end = n.index + leaf_count(n); k < end; ++k) {
        Hit at_tmax;
        at_tmax.t = tmax;
        if (hit_prim(bvh.prims[k], q, at_tmax)) return true;
    }
    return false;
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
/// A piece's hits and visited counts as the wide walks leave them (6 KiB).
struct PieceHits {
    Scratch<Hit, kWideBatch> hits;
    std::uint32_t visited[kWideBatch];
};

/// The calling thread's PieceHits, kept off its stack (ray_batch.h RayPiece says why): made at its
/// first batch query and kept until it ends. Used by one piece at a time: a piece's walks call no
/// batch query.
PieceHits& piece_hits() {
    thread_local const std::unique_ptr<PieceHits> room(new PieceHits);
    return *room;
}

/// The wide nodes the closest-hit walks of a piece's rays visit, on average (for_each_block's
/// probe: how much a batch like them would gain from being reordered); no result is kept.
double probe_wide(const WideBvh& wide, const RayPiece& piece) {
    PieceHits& room = piece_hits();
    std::uint32_t* visited = room.visited;
    intersect_wide_grouped(wide, piece.rays.data(), piece.order, piece.start, room.hits.data(), visited);
    double sum = 0;
    for (std::uint32_t j = 0; j < piece.count; ++j) sum += visited[j];
    return piece.count ? sum / piece.count : 0.0;
}

/// The tree's box, over which the ray order's grid lies (empty for an empty tree).
Aabb scene_box(const Bvh& bvh) { return bvh.empty() ? Aabb{} : node_box(bvh.nodes[0]); }

/// for_each_ray_piece over `block` (a part of `rays`, or its copy in ray order), where a refused
/// ray is named by its index in `rays` (check_rays on the whole batch) rather than in `block`.
template <class Visit>
void trace_block(const RayBatch& rays, const RayBatch& block, std::uint32_t threads, Cancellation* cancel,
                 Visit&& visit) {
    try {
        for_each_ray_piece(block, threads, cancel, std::forward<Visit>(visit));
    } catch (const std::invalid_argument&) {
        check_rays(rays);  // throws, naming the ray in the caller's batch
        throw;
    }
}

}  // namespace

Hit intersect(const Bvh& bvh, const Ray& ray, Traversal mode, std::uint32_t* nodes_visited) {
    NoRecord none;
    return intersect_with(bvh, ray, mode, nodes_visited, none);
}

Hit detail::intersect_recorded(const Bvh& bvh, const Ray& ray, Traversal mode, TraversalRecord& record,
                               const HiddenPrims& hidden, std::uint32_t mesh) {
    Recorder recorder{record, hidden, mesh};
    return intersect_with(bvh, ray, mode, nullptr, recorder);
}

bool occluded(const Bvh& bvh, const Ray& ray, Traversal mode) {
    if (mode == Traversal::Wide) throw std::invalid_argument("use occluded_wide for Traversal::Wide");
    if (bvh.empty()) return false;
    const RayQuery q(ray);
    const float tmax = ray.tmax;  // the boxes are tested up to tmax throughout: no hit lowers it
    bool found = false;
    auto leaf = [&](const BvhNode& n) { return found = leaf_occludes(bvh, n, q, tmax); };
    if (mode == Traversal::Stack) walk::stack(bvh.nodes.data(), q, tmax, leaf);
    else walk::stackless(bvh.nodes.data(), bvh.node_count(), q, tmax, leaf);
    return found;
}

void occluded_batch(const Bvh& bvh, const RayBatch& rays, bool* occluded_out, Traversal mode, std::uint32_t threads,
                    const WideBvh* wide, Cancellation* cancel) {
    if (mode == Traversal::Wide && !wide) throw std::invalid_argument("Traversal::Wide needs the wide tree");
    check_limits(rays);
    if (mode == Traversal::Wide) {  // a piece at once, grouped by octant (wide_kernel.h occluded_wide_grouped)
        const auto probe = [&](const RayPiece& piece) { return probe_wide(*wide, piece); };
        std::unique_ptr<bool[]> in_order;  // a reordered block's answers, in its rays' order
        return for_each_block(rays, scene_box(bvh), probe,
                              // the any-hit walk goes ray by ray (WideWalk is the closest-hit walk's choice)
                              [&](std::size_t base, const RayBatch& block, const SortedRays* sorted, WideWalk) {
                                  if (sorted && !in_order) in_order = std::make_unique<bool[]>(kOrderBlock);
                                  bool* to = sorted ? in_order.get() : occluded_out + base;
                                  trace_block(rays, sorted ? sorted->batch(block) : block, threads, cancel,
                                              [&](std::size_t begin, const RayPiece& piece) {
                                                  occluded_wide_grouped(*wide, piece.rays.data(), piece.order,
                                                                        piece.start, to + begin);
                                              });
                                  if (sorted) unsort(in_order.get(), sorted->index, occluded_out + base);
                              });
    }
    for_each_ray(rays, threads, cancel,
                 [&](std::size_t i, const Ray& ray, float) { occluded_out[i] = occluded(bvh, ray, mode); });
}

void intersect_batch(const Bvh& bvh, const RayBatch& rays, const HitBatch& out, Traversal mode, std::uint32_t threads,
                     const WideBvh* wide, Cancellation* cancel) {
    if (mode == Traversal::Wide && !wide) throw std::invalid_argument("Traversal::Wide needs the wide tree");
    check_limits(rays);             // a negative tmax is refused as occluded_batch refuses it, not answered by misses
    if (mode == Traversal::Wide) {  // a piece at once, grouped by octant (wide_kernel.h intersect_wide_grouped)
        const auto probe = [&](const RayPiece& piece) { return probe_wide(*wide, piece); };
        // the hits of `block`'s pieces to `to` (from its first ray on)
        const auto trace = [&](const RayBatch& block, const HitBatch& to, WideWalk walk) {
            trace_block(rays, block, threads, cancel, [&](std::size_t begin, const RayPiece& piece) {
                PieceHits& room = piece_hits();
                std::uint32_t* v = to.nodes_visited ? room.visited : nullptr;
                intersect_wide_grouped(*wide, piece.rays.data(), piece.order, piece.start, room.hits.data(), v, walk);
                write_hits<true>(to, begin, piece.count, room.hits.data(), v, piece.t_scale, &bvh, piece.rays.data());
            });
        };
        SortedHits in_order;  // a reordered block's hits, in its rays' order
        return for_each_block(rays, scene_box(bvh), probe,
                              [&](std::size_t base, const RayBatch& block, const SortedRays* sorted, WideWalk walk) {
                                  if (!sorted) return trace(block, offset(out, base), walk);
                                  trace(sorted->batch(block), in_order.make(out, block.count), walk);
                                  in_order.unsort(sorted->index, offset(out, base));
                              });
    }
    run_ray_batch(rays, out, threads, cancel, [&](std::size_t, const Ray& ray, std::uint32_t& visited) {
        return intersect(bvh, ray, mode, &visited);
    });
}

}  // namespace bvhlab
