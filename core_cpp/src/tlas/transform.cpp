// transform.cpp — checks, inverse and boxes of instance transforms (transform.h).
#include "bvhlab/transform.h"

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

void validate_transform(const Transform& t, const char* what) {
    for (float x : t.m)
        if (!std::isfinite(x))
            throw std::invalid_argument(std::string(what) + ": the transform has a NaN or infinite entry");
    const double det = det3(t);
    const double bound = column_length(t, 0) * column_length(t, 1) * column_length(t, 2);  // Hadamard: |det| <= bound
    if (!(std::fabs(det) > 1e-6 * bound) || !std::isfinite(det))
        throw std::invalid_argument(std::string(what) +
                                    ": the transform cannot be inverted (a zero-scale axis, or axes "
                                    "(nearly) parallel: determinant " +
                                    std::to_string(det) + ")");
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

Aabb transform_box(const Transform& t, const Aabb& box) {
    if (box.empty()) return box;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int corner = 0; corner < 8; ++corner) {
        const double p[3] = {corner & 1 ? box.hi.x : box.lo.x, corner & 2 ? box.hi.y : box.lo.y,
                             corner & 4 ? box.hi.z : box.lo.z};
        for (int r = 0; r < 3; ++r) {
            const double w = t.m[4 * r] * p[0] + t.m[4 * r + 1] * p[1] + t.m[4 * r + 2] * p[2] + t.m[4 * r + 3];
            lo[r] = std::min(lo[r], w), hi[r] = std::max(hi[r], w);
        }
    }
    Aabb out;
    for (int r = 0; r < 3; ++r) {
        // Rounded outwards: a vertex moved into the world in float, or a ray moved into the object,
        // lands within a few ulps of its exact place.
        const double pad = 0x1p-20 * std::max({std::fabs(lo[r]), std::fabs(hi[r]), hi[r] - lo[r]});
        out.lo[r] = std::nextafter(float(lo[r] - pad), -INFINITY);
        out.hi[r] = std::nextafter(float(hi[r] + pad), INFINITY);
    }
    return out;
}

}  // namespace bvhlab
