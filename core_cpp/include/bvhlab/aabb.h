// aabb.h — axis-aligned bounding box (the only bounding volume the report uses, §1).
#pragma once
#include <limits>
#include "bvhlab/vec3.h"

namespace bvhlab {

/// An axis-aligned box. Default-constructed it is empty (lo = +inf, hi = -inf), so growing it
/// by anything yields that thing, and its half area is 0.
struct Aabb {
    Vec3 lo{std::numeric_limits<float>::infinity()};
    Vec3 hi{-std::numeric_limits<float>::infinity()};

    void grow(Vec3 p) {
        lo = min(lo, p);
        hi = max(hi, p);
    }
    void grow(const Aabb& b) {
        lo = min(lo, b.lo);
        hi = max(hi, b.hi);
    }
    bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    Vec3 extent() const { return hi - lo; }
    Vec3 center() const { return (lo + hi) * 0.5f; }
    /// Half the surface area: the SAH only ever compares ratios of areas.
    float half_area() const {
        if (empty()) return 0.0f;
        Vec3 e = extent();
        return e.x * e.y + e.y * e.z + e.z * e.x;
    }
    bool contains(const Aabb& b) const {
        return lo.x <= b.lo.x && lo.y <= b.lo.y && lo.z <= b.lo.z && hi.x >= b.hi.x && hi.y >= b.hi.y && hi.z >= b.hi.z;
    }
};

}  // namespace bvhlab
