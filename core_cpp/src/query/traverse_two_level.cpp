// traverse_two_level.cpp — closest hits through a TLAS and its BLASes (tlas.h): the TLAS is walked
// with the walks of every tree (walk.h); at an instance the ray is moved into its object space
// (origin and direction by the inverse transform, the direction left unnormalised so that t is
// the same in both spaces) and the BLAS is traversed up to the closest hit so far. The any-hit
// query (occluded) is the same walk of both levels, ended at the first instance with a hit.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "bvhlab/coordinate_range.h"
#include "bvhlab/ray.h"
#include "bvhlab/tlas.h"
#include "bvhlab/two_level_record.h"
#include "bvhlab/wide_bvh.h"
#include "object_ray.h"
#include "ray_batch.h"
#include "walk.h"
#include "wide_kernel.h"
#include "wide_kernels.h"

namespace bvhlab {
namespace {

/// The TLAS's box test: hit_box's (ray.h) arithmetic, the same products and the same order of
/// raises and lowers, so the same t's bit for bit, but each axis's near and far plane picked by the
/// ray's signs once per ray (offsets among the node's floats, as the wide walk's kPlanes), not by
/// three branches per box, which random directions mispredict. A TLAS has no triangles, so none
/// of make_ray's axes and shear: the origin and the IEEE inverse direction alone of the
/// world ray.
struct TlasQuery {
    float origin[3], inv_dir[3], tmin;
    int near[3], far[3];  ///< floats from a BvhNode's start: lo.x, lo.y, lo.z at 0-2, hi at 4-6
    TlasQuery(const float* o, const float* inv, float t_min) : tmin(t_min) {
        for (int a = 0; a < 3; ++a) {
            origin[a] = o[a], inv_dir[a] = inv[a];
            near[a] = a + (std::signbit(inv[a]) ? 4 : 0), far[a] = near[a] ^ 4;
        }
    }
};
static_assert(offsetof(BvhNode, hi) == 4 * sizeof(float));

[[gnu::always_inline]] inline bool hit_box(const BvhNode& n, const TlasQuery& q, float tmax, float& t_enter) {
    const float* f = reinterpret_cast<const float*>(&n);
    const float near_x = (f[q.near[0]] - q.origin[0]) * q.inv_dir[0];
    const float near_y = (f[q.near[1]] - q.origin[1]) * q.inv_dir[1];
    const float near_z = (f[q.near[2]] - q.origin[2]) * q.inv_dir[2];
    const float far_x = (f[q.far[0]] - q.origin[0]) * q.inv_dir[0];
    const float far_y = (f[q.far[1]] - q.origin[1]) * q.inv_dir[1];
    const float far_z = (f[q.far[2]] - q.origin[2]) * q.inv_dir[2];
    const float t0 = raise_to(raise_to(raise_to(q.tmin, near_x), near_y), near_z);
    const float t1 = lower_to(lower_to(lower_to(tmax, far_x), far_y), far_z) * gpu::BOX_FAR_SCALE;
    t_enter = t0;
    return t0 <= t1;
}

/// The world ray as every instance starts from it: scaled once (scale_ray, exact; a batch's rays
/// are scaled already, so this is nothing for them). Its t times `t_scale` is the caller's.
struct WorldRay {
    Ray ray;
    float t_scale;
    explicit WorldRay(const Ray& r) : ray(r), t_scale(scale_ray(ray)) {}
    /// The binary TLAS's box test for this ray (the wide TLAS's is the wide walk's, start_tlas_walk).
    TlasQuery boxes() const {
        const float o[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
        const float inv[3] = {1.0f / ray.dir.x, 1.0f / ray.dir.y, 1.0f / ray.dir.z};  // IEEE, as make_ray
        return TlasQuery(o, inv, ray.tmin);
    }
};

/// Calls `visit(inst)` for the instances of the TLAS leaf whose first is at `first` in
/// tlas.leaf_instances (where a wide TLAS leaf word points, a binary leaf's index), in their order,
/// until `visit` returns true; returns whether it did.
template <class Visit>
bool any_of_leaf(const Tlas& tlas, std::uint32_t first, Visit&& visit) {
    for (std::uint32_t k = first;; ++k) {
        const LeafInstance& inst = tlas.leaf_instances[k];
        if (visit(inst)) return true;
        if (inst.last) return false;
    }
}

/// What the closest-hit walk reports of its steps: nothing (every query; the calls compile to the
/// code they were), or each step to the inspector's recorder (two_level_record.h).
struct NoSteps {
    static constexpr bool kRecorded = false;
    void box(std::uint32_t, bool) {}
    /// The BLAS walk of `mode`, the wide one by kernel set K (wide_kernels.h: picked once a query)
    template <class K>
    Hit enter(std::uint32_t, std::uint32_t, const BlasView& blas, const Ray& ray, Traversal mode,
              std::uint32_t* visited) {
        return mode == Traversal::Wide ? intersect_wide_with<K>(blas, ray, visited)
                                       : intersect(*blas.bvh, ray, mode, visited);
    }
    void entered(bool, float) {}
};
struct RecordedSteps {
    static constexpr bool kRecorded = true;
    TwoLevelRecorder& r;
    void box(std::uint32_t node, bool hit) { r.box(node, hit); }
    template <class>
    Hit enter(std::uint32_t leaf, std::uint32_t index, const BlasView& blas, const Ray& ray, Traversal mode,
              std::uint32_t* visited) {
        return r.instance(leaf, index, blas, ray, mode, visited);
    }
    void entered(bool closer, float t_scale) { r.instance_done(closer, t_scale); }
};

/// The recorder's view of the wide TLAS walk (wide_kernel.h next_tlas_leaf): each wide node visited
/// is the box tests of its children, named by the binary nodes they stand for (an inner child's
/// WideNode::unused[1], a leaf child's LeafInstance::leaf), entered where the walk went on to the
/// child or pushed it.
class WideTlasBoxes final : public WideRecorder {
public:
    WideTlasBoxes(const Tlas& tlas, TwoLevelRecorder& r) : tlas_(tlas), r_(r) {}
    void node(std::uint32_t line, std::uint32_t nearest, const std::uint32_t* pushed, std::uint32_t count) override {
        const WideNode& n = tlas_.wide.node(line);
        for (std::uint32_t k = 0; k < n.unused[0]; ++k) {
            const std::uint32_t c = n.child[k];
            const std::uint32_t name =
                (c & kLeafChild) ? tlas_.leaf_instances[c & ~kLeafChild].leaf : tlas_.wide.node(c).unused[1];
            r_.box(name, c == nearest || std::find(pushed, pushed + count, c) != pushed + count);
        }
    }
    void leaf(std::uint32_t, const Hit&, const Hit&) override {}

private:
    const Tlas& tlas_;
    TwoLevelRecorder& r_;
};

/// Tests instance `inst` with the world ray, whose closest hit so far is `best` (t in the world
/// ray's scaled units), its wide walk by kernel set K.
template <class K, class Steps>
void test_instance(const TwoLevel& scene, const LeafInstance& inst, const WorldRay& world, Traversal mode,
                   InstanceHit& best, std::uint32_t& visited, Steps& steps) {
    Ray ray;
    float t_scale;
    if (!object_ray(inst, world.ray, best.hit.t, ray, t_scale)) return;
    std::uint32_t count = 0;
    Hit h = steps.template enter<K>(inst.leaf, inst.instance, scene.blases[inst.blas], ray, mode, &count);
    visited += count;
    if (h.ref == kNoHit) return steps.entered(false, t_scale * world.t_scale);
    h.t *= t_scale;
    const bool closer = h.t < best.hit.t;
    steps.entered(closer, t_scale * world.t_scale);
    if (closer) best.hit = h, best.instance = inst.instance;
}

/// Whether instance `inst` holds a hit of the world ray before its tmax (the wide walk by kernel set K).
template <class K>
bool instance_occludes(const TwoLevel& scene, const LeafInstance& inst, const WorldRay& world, Traversal mode) {
    const BlasView& blas = scene.blases[inst.blas];
    Ray ray;
    float t_scale;
    if (!object_ray(inst, world.ray, world.ray.tmax, ray, t_scale)) return false;
    return mode == Traversal::Wide ? K::any(view_of(*blas.wide), ray) : occluded(*blas.bvh, ray, mode);
}

/// The TLAS walk of `mode` (stackless for Traversal::Stackless, else with a stack) up to `hit_t`,
/// `leaf` testing a leaf's instances (walk.h: returning true ends the walk), `on_box` told of each
/// box test (walk.h).
template <class Leaf, class OnBox = walk::NoBoxes>
std::uint32_t walk_tlas(const Tlas& tlas, const TlasQuery& q, const float& hit_t, Traversal mode, Leaf&& leaf,
                        OnBox&& on_box = OnBox{}) {
    return mode == Traversal::Stackless
               ? walk::stackless(tlas.tree.nodes.data(), tlas.tree.node_count(), q, hit_t, leaf, on_box)
               : walk::stack(tlas.tree.nodes.data(), q, hit_t, leaf, on_box);
}

/// The TLAS's box, over which the ray order's grid lies (ray_order.h; empty for an empty TLAS).
Aabb tlas_box(const Tlas& tlas) { return tlas.tree.empty() ? Aabb{} : node_box(tlas.tree.nodes[0]); }

}  // namespace

void check_two_level(const TwoLevel& scene, Traversal mode) {
    if (!scene.tlas) throw std::invalid_argument("a two-level query needs a TLAS");
    for (const BlasView& b : scene.blases) {
        if (!b.bvh) throw std::invalid_argument("a mesh of the two-level query has no tree");
        if (mode == Traversal::Wide && !b.wide)
            throw std::invalid_argument("Traversal::Wide needs every mesh's wide tree");
    }
    for (const Instance& inst : scene.tlas->instances)
        if (inst.blas >= scene.blases.size())
            throw std::invalid_argument("the TLAS refers to mesh " + std::to_string(inst.blas) +
                                        ", but the query has " + std::to_string(scene.blases.size()));
}

namespace {

/// The closest-hit walk of both levels, the wide walks by kernel set K. The one-identity-instance
/// case is the recorder's alone: intersect_two_level answers it inline (tlas.h) before
/// intersect_through_tlas, so the query's walk does not test it again.
template <class K, class Steps>
InstanceHit intersect_two_level_with(const TwoLevel& scene, const Ray& ray, Traversal mode,
                                     std::uint32_t* nodes_visited, Steps& steps) {
    const Tlas& tlas = *scene.tlas;
    InstanceHit best;
    best.hit.t = ray.tmax;
    std::uint32_t visited = 0;
    if (Steps::kRecorded && one_identity_instance(tlas)) {
        // One mesh where it was modelled: the flat query, no TLAS box in the way.
        best.hit = steps.template enter<K>(kNoHit, 0, scene.blases[tlas.instances[0].blas], ray, mode, &visited);
        steps.entered(best.hit.ref != kNoHit, 1.0f);
        if (best.hit.ref != kNoHit) best.instance = 0;
    } else if (!tlas.tree.empty()) {
        const WorldRay world(ray);
        best.hit.t = world.ray.tmax;
        auto leaf_from = [&](std::uint32_t first) {
            any_of_leaf(tlas, first, [&](const LeafInstance& inst) {
                test_instance<K>(scene, inst, world, mode, best, visited, steps);
                return false;
            });
        };
        if (mode == Traversal::Wide) {
            TlasWalk walk;
            K::start_tlas(world.ray, walk);
            auto walk_to_end = [&](WideRecorder* record) {
                const WideView view = view_of(tlas.wide);
                for (std::uint32_t k; (k = K::next_tlas(view, walk, best.hit.t, record)) != kNoHit;) leaf_from(k);
            };
            if constexpr (Steps::kRecorded) {
                WideTlasBoxes boxes(tlas, steps.r);
                walk_to_end(&boxes);
            } else {
                walk_to_end(nullptr);
            }
            visited += walk.visited;
        } else {
            auto leaf = [&](const BvhNode& n) { leaf_from(n.index); };
            visited += walk_tlas(tlas, world.boxes(), best.hit.t, mode, leaf,
                                 [&](std::uint32_t node, bool entered) { steps.box(node, entered); });
        }
        best.hit.t *= world.t_scale;  // the caller's units (a miss's tmax is replaced below)
    }
    if (best.hit.ref == kNoHit) best.hit.t = kInfinity;
    if (nodes_visited) *nodes_visited = visited;
    return best;
}

}  // namespace

InstanceHit detail::intersect_through_tlas(const TwoLevel& scene, const Ray& ray, Traversal mode,
                                           std::uint32_t* nodes_visited) {
    NoSteps none;
    return with_wide_kernels(
        [&](auto k) { return intersect_two_level_with<decltype(k)>(scene, ray, mode, nodes_visited, none); });
}

InstanceHit detail::intersect_two_level_recorded(const TwoLevel& scene, const Ray& ray, Traversal mode,
                                                 TwoLevelRecorder& recorder, std::uint32_t* nodes_visited) {
    RecordedSteps steps{recorder};
    return with_wide_kernels(
        [&](auto k) { return intersect_two_level_with<decltype(k)>(scene, ray, mode, nodes_visited, steps); });
}

void intersect_batch_two_level(const TwoLevel& scene, const RayBatch& rays, const HitBatch& hits,
                               std::int32_t* instance, Traversal mode, std::uint32_t threads, Cancellation* cancel) {
    check_two_level(scene, mode);
    check_limits(rays);
    const Tlas& tlas = *scene.tlas;
    if (one_identity_instance(tlas)) {
        // One mesh where it was modelled: the flat batch itself, every hit in instance 0
        const BlasView& blas = scene.blases[tlas.instances[0].blas];
        intersect_batch(*blas.bvh, rays, hits, mode, threads, blas.wide, cancel);
        if (instance)
            for (std::size_t i = 0; i < rays.count; ++i) instance[i] = hits.prim[i] < 0 ? -1 : 0;
        return;
    }
    check_rays(rays);  // once: a reordered block's copy would name a refused ray by its place there
    // the hits of `block`'s rays to `to` and `inst` (from its first ray on)
    const auto trace = [&](const RayBatch& block, const HitBatch& to, std::int32_t* inst) {
        const auto one = [&](std::size_t i, const Ray& ray, std::uint32_t& visited) {
            const InstanceHit h = detail::intersect_through_tlas(scene, ray, mode, &visited);
            if (inst) inst[i] = h.hit.ref == kNoHit ? -1 : std::int32_t(h.instance);
            return h.hit;
        };
        run_ray_batch(block, to, threads, cancel, one, true);
    };
    const auto probe = [&](const RayPiece& piece) {
        double t = 0;  // the hits summed: the probe is timed (for_each_block<false>) and must not be dropped
        for (std::uint32_t j = 0; j < piece.count; ++j)
            t += detail::intersect_through_tlas(scene, piece.rays[j], mode, nullptr).hit.t;
        return t;
    };
    SortedHits in_order;                        // a reordered block's hits, in its rays' order
    BigVector<std::int32_t> instance_in_order;  // as SortedHits: grown without a fill
    for_each_block<false>(rays, tlas_box(tlas), probe,
                          [&](std::size_t base, const RayBatch& block, const SortedRays* sorted, WideWalk) {
                              if (!sorted)
                                  return trace(block, offset(hits, base), instance ? instance + base : nullptr);
                              instance_in_order.resize(instance ? block.count : 0);
                              trace(sorted->batch(block), in_order.make(hits, block.count),
                                    instance ? instance_in_order.data() : nullptr);
                              in_order.unsort(sorted->index, offset(hits, base));
                              if (instance) unsort(instance_in_order.data(), sorted->index, instance + base);
                          });
}

}  // namespace bvhlab

namespace bvhlab {

namespace {

/// occluded_through_tlas by kernel set K (wide_kernels.h).
template <class K>
bool occluded_through_tlas_with(const TwoLevel& scene, const Ray& ray, Traversal mode) {
    const Tlas& tlas = *scene.tlas;
    if (tlas.tree.empty()) return false;
    const WorldRay world(ray);
    auto leaf_from = [&](std::uint32_t first) {
        return any_of_leaf(tlas, first,
                           [&](const LeafInstance& inst) { return instance_occludes<K>(scene, inst, world, mode); });
    };
    if (mode == Traversal::Wide) {  // the closest-hit walk of the wide TLAS, its far limit tmax throughout
        TlasWalk walk;
        K::start_tlas(world.ray, walk);
        const WideView view = view_of(tlas.wide);
        for (std::uint32_t k; (k = K::next_tlas(view, walk, world.ray.tmax, nullptr)) != kNoHit;)
            if (leaf_from(k)) return true;
        return false;
    }
    bool found = false;
    walk_tlas(tlas, world.boxes(), world.ray.tmax, mode, [&](const BvhNode& n) { return found = leaf_from(n.index); });
    return found;
}

}  // namespace

bool detail::occluded_through_tlas(const TwoLevel& scene, const Ray& ray, Traversal mode) {
    return with_wide_kernels([&](auto k) { return occluded_through_tlas_with<decltype(k)>(scene, ray, mode); });
}

void occluded_batch_two_level(const TwoLevel& scene, const RayBatch& rays, bool* occluded, Traversal mode,
                              std::uint32_t threads, Cancellation* cancel) {
    check_two_level(scene, mode);
    const Tlas& tlas = *scene.tlas;
    if (one_identity_instance(tlas)) {  // the flat batch, as intersect_batch_two_level
        const BlasView& blas = scene.blases[tlas.instances[0].blas];
        return occluded_batch(*blas.bvh, rays, occluded, mode, threads, blas.wide, cancel);
    }
    check_limits(rays);
    check_rays(rays);  // once, as intersect_batch_two_level
    const auto trace = [&](const RayBatch& block, bool* to) {
        const auto one = [&](std::size_t i, const Ray& ray, float) {
            to[i] = detail::occluded_through_tlas(scene, ray, mode);
        };
        for_each_ray(block, threads, cancel, one, true);
    };
    const auto probe = [&](const RayPiece& piece) {
        double blocked = 0;  // counted: the probe is timed and must not be dropped
        for (std::uint32_t j = 0; j < piece.count; ++j)
            blocked += detail::occluded_through_tlas(scene, piece.rays[j], mode);
        return blocked;
    };
    std::unique_ptr<bool[]> in_order;  // a reordered block's answers, in its rays' order
    for_each_block<false>(rays, tlas_box(tlas), probe,
                          [&](std::size_t base, const RayBatch& block, const SortedRays* sorted, WideWalk) {
                              if (!sorted) return trace(block, occluded + base);
                              if (!in_order) in_order = std::make_unique<bool[]>(kOrderBlock);
                              trace(sorted->batch(block), in_order.get());
                              unsort(in_order.get(), sorted->index, occluded + base);
                          });
}

}  // namespace bvhlab
