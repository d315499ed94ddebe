// ray_checks.cpp — the rays intersect_batch accepts (coordinate_range.h says why these).
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "bvhlab/coordinate_range.h"
#include "bvhlab/traverse.h"

namespace bvhlab {

namespace {
bool valid_tmax(float tmax) { return tmax >= 0.0f; }  // false for NaN too

/// "WHAT: LIMIT must be a number >= 0[ (inf for no limit)], got VALUE"
std::string limit_message(const std::string& what, const char* limit, float value) {
    char got[32];
    std::snprintf(got, sizeof got, "%g", double(value));
    const bool far = std::string(limit) == "tmax";
    return what + ": " + limit + " must be a number >= 0" + (far ? " (inf for no limit)" : "") + ", got " + got;
}
}  // namespace

void check_limits(const RayBatch& rays) {  // each ray's own tmax: check_rays
    // A negative tmin is no ray segment the walks can answer: the far side of a box is widened by
    // scaling its distance (ray.h hit_box), which narrows it where that distance is negative, so
    // boxes flat on an axis behind the origin would be missed (Embree and OptiX take tnear >= 0 too)
    if (!(rays.tmin >= 0.0f)) throw std::invalid_argument(limit_message("the rays", "tmin", rays.tmin));
    if (!rays.tmax_of && !valid_tmax(rays.tmax))
        throw std::invalid_argument(limit_message("the rays", "tmax", rays.tmax));
}

void check_rays(const RayBatch& rays) {
    bool all_in_range = true;
    for (std::size_t i = 0; i < rays.count; ++i) {  // without branches: coordinate_range.h
        const float* o = rays.origins + 3 * i;
        const float* d = rays.directions + 3 * i;
        all_in_range &= in_coordinate_range(Vec3{o[0], o[1], o[2]}) & direction_in_range(Vec3{d[0], d[1], d[2]});
    }
    for (std::size_t i = 0; rays.tmax_of && i < rays.count; ++i) all_in_range &= valid_tmax(rays.tmax_of[i]);
    if (all_in_range) return;
    // a ray is refused: the first one, tmax first, as before
    for (std::size_t i = 0; rays.tmax_of && i < rays.count; ++i)
        if (!valid_tmax(rays.tmax_of[i]))
            throw std::invalid_argument(limit_message("ray " + std::to_string(i), "tmax", rays.tmax_of[i]));
    for (std::size_t i = 0; i < rays.count; ++i) {
        const float* o = rays.origins + 3 * i;
        const float* d = rays.directions + 3 * i;
        const Vec3 origin{o[0], o[1], o[2]}, dir{d[0], d[1], d[2]};
        if (in_coordinate_range(origin) && direction_in_range(dir)) continue;
        const std::string ray = "ray " + std::to_string(i);
        if (!all_finite(origin) || !all_finite(dir))
            throw std::invalid_argument(ray + ": origin and direction must be finite (no NaN or inf)");
        if (!in_coordinate_range(origin))
            throw std::invalid_argument(ray +
                                        " starts outside the supported coordinate range [-2^40, 2^40] "
                                        "(±1.0995e12), where float32 ray tests would overflow");
        char got[32];
        std::snprintf(got, sizeof got, "%g", double(largest_component(dir)));
        throw std::invalid_argument(ray +
                                    ": the largest |component| of a direction must be in [2^-80, 2^80] "
                                    "(8.3e-25 to 1.2e24), got " +
                                    got);
    }
}

}  // namespace bvhlab
