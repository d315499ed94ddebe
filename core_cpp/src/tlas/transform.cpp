// transform.cpp — checks, inverse and boxes of instance transforms (transform.h).
#include "bvhlab/transform.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace bvhlab {
namespace {

double det3(const Transform& t) {
    const auto& m = t.m;
    auto d = [&](int i) { return double(m[i]); };
    return d(0) * (d(5) * d(10) - d(6) * d(9)) - d(1) * (d(4) * d(10) - d(6) * d(8)) +
           d(2) * (d(4) * d(9) - d(5) * d(8));
}

double column_length(const Transform& t, int c) {
    const double x = t.m[c], y = t.m[4 + c], z = t.m[8 + c];
    return std::sqrt(x * x + y * y + z * z);
}

}  // namespace

bool transform_invertible(const Transform& t) {
    for (float x : t.m)
        if (!std::isfinite(x)) return false;
    const double det = det3(t);
    const double bound = column_length(t, 0) * column_length(t, 1) * column_length(t, 2);  // Hadamard: |det| <= bound
    return std::fabs(det) > 1e-6 * bound && std::isfinite(det);
}

void validate_transform(const Transform& t, const char* what) {
    if (transform_invertible(t)) return;
    for (float x : t.m)
        if (!std::isfinite(x))
            throw std::invalid_argument(std::string(what) + ": the transform has a NaN or infinite entry");
    throw std::invalid_argument(std::string(what) +
                                ": the transform cannot be inverted (a zero-scale axis, or axes "
                                "(nearly) parallel: determinant " +
                                std::to_string(det3(t)) + ")");
}

Transform inverse(const Transform& t) {
    const auto& m = t.m;
    auto d = [&](int i) { return double(m[i]); };
    const double inv_det = 1.0 / det3(t);
    // The adjugate of the linear part over the determinant, then -A^-1 · translation.
    double a[9] = {(d(5) * d(10) - d(6) * d(9)) * inv_det, (d(2) * d(9) - d(1) * d(10)) * inv_det,
                   (d(1) * d(6) - d(2) * d(5)) * inv_det,  (d(6) * d(8) - d(4) * d(10)) * inv_det,
                   (d(0) * d(10) - d(2) * d(8)) * inv_det, (d(2) * d(4) - d(0) * d(6)) * inv_det,
                   (d(4) * d(9) - d(5) * d(8)) * inv_det,  (d(1) * d(8) - d(0) * d(9)) * inv_det,
                   (d(0) * d(5) - d(1) * d(4)) * inv_det};
    Transform out;
    for (int r = 0; r < 3; ++r) {
        const double tr = -(a[3 * r] * d(3) + a[3 * r + 1] * d(7) + a[3 * r + 2] * d(11));
        out.m[4 * r] = float(a[3 * r]), out.m[4 * r + 1] = float(a[3 * r + 1]), out.m[4 * r + 2] = float(a[3 * r + 2]);
        out.m[4 * r + 3] = float(tr);
    }
    return out;
}

Aabb transform_boxes(const Transform& t, const Aabb* boxes, std::size_t count) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t k = 0; k < count; ++k) {
        const Aabb& box = boxes[k];
        if (box.empty()) continue;
        // Arvo (Graphics Gems, 1990): the moved centre, and the half extent through |M|
        const double c[3] = {0.5 * (double(box.lo.x) + box.hi.x), 0.5 * (double(box.lo.y) + box.hi.y),
                             0.5 * (double(box.lo.z) + box.hi.z)};
        const double h[3] = {0.5 * (double(box.hi.x) - box.lo.x), 0.5 * (double(box.hi.y) - box.lo.y),
                             0.5 * (double(box.hi.z) - box.lo.z)};
        for (int r = 0; r < 3; ++r) {
            const double m0 = t.m[4 * r], m1 = t.m[4 * r + 1], m2 = t.m[4 * r + 2];
            const double centre = m0 * c[0] + m1 * c[1] + m2 * c[2] + t.m[4 * r + 3];
            const double half = std::fabs(m0) * h[0] + std::fabs(m1) * h[1] + std::fabs(m2) * h[2];
            lo[r] = std::min(lo[r], centre - half), hi[r] = std::max(hi[r], centre + half);
        }
    }
    Aabb out;
    if (lo[0] > hi[0]) return out;  // nothing but empty boxes
    for (int r = 0; r < 3; ++r) {
        // Rounded outwards: a vertex moved into the world in float, or a ray moved into the object,
        // lands within a few ulps of its exact place.
        const double pad = 0x1p-20 * std::max({std::fabs(lo[r]), std::fabs(hi[r]), hi[r] - lo[r]});
        out.lo[r] = std::nextafter(float(lo[r] - pad), -INFINITY);
        out.hi[r] = std::nextafter(float(hi[r] + pad), INFINITY);
    }
    return out;
}

Aabb transform_box(const Transform& t, const Aabb& box) { return transform_boxes(t, &box, 1); }

}  // namespace bvhlab
