// chop.cpp — clipping a triangle by a plane for the spatial splits (chop.h).
#include "chop.h"

#include <algorithm>
#include <cmath>

namespace bvhlab::sbvh {
/// p = a + (b - a)·t in float is off by a few ulps of |a| + |b| on the other two axes
/// (one rounding in b - a, one in t, one in the product and one in the sum), so it is widened by
/// 2^-20 (|a| + |b|), eight ulps of it.
Aabb edge_crossing(Vec3 a, Vec3 b, int axis, float pos) {
    const float t = (pos - a[axis]) / (b[axis] - a[axis]);
    Aabb box;
    for (int k = 0; k < 3; ++k) {
        if (k == axis) {
            box.lo[k] = box.hi[k] = pos;
            continue;
        }
        const float p = a[k] + (b[k] - a[k]) * t;
        const float err = (std::fabs(a[k]) + std::fabs(b[k])) * 0x1p-20f;
        box.lo[k] = p - err, box.hi[k] = p + err;
    }
    return box;
}

void chop_triangle(const Vec3 v[3], const Aabb& box, int axis, float pos, Aabb& below, Aabb& above) {
    Aabb lo_part, hi_part;
    for (int k = 0; k < 3; ++k) {
        const Vec3 a = v[k], b = v[k == 2 ? 0 : k + 1];
        if (a[axis] <= pos) lo_part.grow(a);
        if (a[axis] >= pos) hi_part.grow(a);
        if ((a[axis] < pos && pos < b[axis]) || (b[axis] < pos && pos < a[axis])) {
            const Aabb p = edge_crossing(a, b, axis, pos);
            lo_part.grow(p), hi_part.grow(p);
        }
    }
    lo_part.hi[axis] = std::min(lo_part.hi[axis], pos);
    hi_part.lo[axis] = std::max(hi_part.lo[axis], pos);
    below = intersect(lo_part, box);
    above = intersect(hi_part, box);
}

void chop_box(const Aabb& box, int axis, float pos, Aabb& below, Aabb& above) {
    below = above = box;
    below.hi[axis] = std::min(below.hi[axis], pos);
    above.lo[axis] = std::max(above.lo[axis], pos);
}

void chop_reference(const GeometryView& g, const PrimRef& r, int axis, float pos, Aabb& below, Aabb& above) {
    if (is_sphere_ref(r.ref)) return chop_box(r.box(), axis, pos, below, above);
    const std::size_t i = ref_index(r.ref);
    const Vec3 v[3] = {g.vertex(i, 0), g.vertex(i, 1), g.vertex(i, 2)};
    chop_triangle(v, r.box(), axis, pos, below, above);
}

}  // namespace bvhlab::sbvh
