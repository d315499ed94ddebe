// clip_polygon.h — a triangle cut by axis-aligned planes, in double: the clip and the area that
// the node figures' EPO (epo.cpp) and the saved SBVH's coverage check (coverage.cpp) share.
#pragma once
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bvhlab {

/// A convex polygon: a triangle cut by axis-aligned half-spaces is the triangle within a box, at
/// most 3 + 6 corners (a plane it does not cross, or meets at a corner, adds none).
struct ClipPolygon {
    static constexpr int kMostCorners = 9;
    double p[kMostCorners][3];
    int n = 0;
};

/// Sutherland–Hodgman: `out` is the part of `in` with sign·(x[axis] - plane) <= 0; a crossing
/// point lies exactly on the plane, whatever the rounding of where along its edge.
inline void clip(const ClipPolygon& in, ClipPolygon& out, int axis, double plane, double sign) {
    out.n = 0;
    for (int i = 0; i < in.n; ++i) {
        const double* a = in.p[i];
        const double* b = in.p[(i + 1) % in.n];
        const double da = sign * (a[axis] - plane), db = sign * (b[axis] - plane);
        const bool crosses = (da < 0 && db > 0) || (da > 0 && db < 0);
        if (out.n + (da <= 0) + crosses > ClipPolygon::kMostCorners)
            throw std::logic_error("a triangle cut by axis-aligned planes with more corners than a box can cut");
        if (da <= 0) std::copy(a, a + 3, out.p[out.n++]);
        if (crosses) {
            const double s = da / (da - db);
            double* q = out.p[out.n++];
            for (int k = 0; k < 3; ++k) q[k] = a[k] + s * (b[k] - a[k]);
            q[axis] = plane;
        }
    }
}

/// The area of a planar polygon (half the length of Σ p_i × p_{i+1}, its vector area).
inline double polygon_area(const ClipPolygon& poly) {
    double sx = 0, sy = 0, sz = 0;
    for (int i = 0; i < poly.n; ++i) {
        const double* a = poly.p[i];
        const double* b = poly.p[(i + 1) % poly.n];
        sx += a[1] * b[2] - a[2] * b[1], sy += a[2] * b[0] - a[0] * b[2], sz += a[0] * b[1] - a[1] * b[0];
    }
    return 0.5 * std::sqrt(sx * sx + sy * sy + sz * sz);
}

}  // namespace bvhlab
