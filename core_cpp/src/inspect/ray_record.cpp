// ray_record.cpp — one ray's traversal, recorded by the traversal code itself (traverse.cpp; the
// wide walk: wide_record.cpp).
#include "bvhlab/ray_record.h"

#include <stdexcept>

#include "bvhlab/coordinate_range.h"

namespace bvhlab {
namespace {

/// The checks and scaling of intersect_batch, then `walk(scaled ray, record)` giving the hit, whose t
/// goes back to the ray's own units.
template <class Walk>
TraversalRecord recorded(Ray ray, Walk&& walk) {
    const float origin[3] = {ray.origin.x, ray.origin.y, ray.origin.z}, dir[3] = {ray.dir.x, ray.dir.y, ray.dir.z};
    check_rays(RayBatch{origin, dir, 1, ray.tmin, ray.tmax});
    const float t_scale = scale_ray(ray);
    TraversalRecord record;
    record.hit = walk(ray, record);
    record.hit.t *= t_scale;  // inf stays inf
    if (record.hit.ref == kNoHit) record.hit_leaf = kNoHit;
    return record;
}

}  // namespace

TraversalRecord record_traversal(const Bvh& bvh, Ray ray, Traversal mode, const HiddenPrims& hidden) {
    if (mode == Traversal::Wide)
        throw std::invalid_argument("record_traversal: the wide walk is record_wide_traversal");
    return recorded(ray, [&](const Ray& scaled, TraversalRecord& record) {
        const Hit hit = detail::intersect_recorded(bvh, scaled, mode, record, hidden);
        record.nodes_visited = std::uint32_t(record.box_nodes.size());
        return hit;
    });
}

TraversalRecord record_wide_traversal(const Bvh& bvh, const WideBvh& wide, const WideNames& names, Ray ray) {
    return recorded(ray, [&](const Ray& scaled, TraversalRecord& record) {
        return detail::intersect_wide_recorded(bvh, wide, names, scaled, record);
    });
}

}  // namespace bvhlab
