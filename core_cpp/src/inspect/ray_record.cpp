// ray_record.cpp — one ray's traversal, recorded by the traversal code itself (traverse.cpp).
#include "bvhlab/ray_record.h"

#include <stdexcept>

#include "bvhlab/coordinate_range.h"

namespace bvhlab {

TraversalRecord record_traversal(const Bvh& bvh, Ray ray, Traversal mode) {
    if (mode == Traversal::Wide)
        throw std::invalid_argument("a traversal record names binary nodes: use traversal stack or stackless");
    const float origin[3] = {ray.origin.x, ray.origin.y, ray.origin.z}, dir[3] = {ray.dir.x, ray.dir.y, ray.dir.z};
    check_rays(RayBatch{origin, dir, 1, ray.tmin, ray.tmax});  // the checks and scaling of intersect_batch
    const float t_scale = scale_ray(ray);
    TraversalRecord record;
    record.hit = detail::intersect_recorded(bvh, ray, mode, record);
    record.hit.t *= t_scale;  // inf stays inf
    if (record.hit.ref == kNoHit) record.hit_leaf = kNoHit;
    return record;
}

}  // namespace bvhlab
