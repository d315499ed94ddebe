// The default camera and light (render_defaults.h), in double precision like the Python floats they
// become.
#include "bvhlab/render_defaults.h"

#include <algorithm>
#include <cmath>

#include "bvhlab/coordinate_range.h"

namespace bvhlab {
namespace {

using D3 = std::array<double, 3>;

D3 sub(const D3& a, const D3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
D3 add_scaled(const D3& a, const D3& b, double s) { return {a[0] + b[0] * s, a[1] + b[1] * s, a[2] + b[2] * s}; }
double norm(const D3& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }
D3 cross(const D3& a, const D3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
D3 d3(Vec3 v) { return {v.x, v.y, v.z}; }

/// The point nearest `p` on the segment from `inside` (within the coordinate range) to `p` that
/// lies within the range, with a margin where `inside` leaves room for one: the default light of a
/// camera near the range's edge stood outside it, and the scene was refused for a light it did not
/// have (geometry at x = 1e12, within 2^40: "light position ... outside the supported range"). (A
/// default camera that would stand outside is not made: Scene leaves the camera to the caller.)
D3 pulled_within_range(const D3& inside, const D3& p) {
    double s = 1.0;
    for (int k = 0; k < 3; ++k) {
        const double limit = std::max(double(kMaxCoordinate) * 0.99, std::fabs(inside[k]));
        const double d = p[k] - inside[k];
        if (std::fabs(p[k]) > limit && d != 0.0) s = std::min(s, ((d > 0 ? limit : -limit) - inside[k]) / d);
    }
    return add_scaled(inside, sub(p, inside), std::max(s, 0.0));
}

}  // namespace

CameraPlacement default_camera(const Aabb& bounds) {
    if (bounds.empty()) return {kFallbackCameraPosition, kFallbackCameraTarget, {0, 0, 1}, kDefaultFovY};
    const D3 lo = d3(bounds.lo), hi = d3(bounds.hi);
    const D3 center{(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2};
    // A point-like scene still gets a camera some way off, measurably so in float32 even far from
    // the origin (at 1e12 a float32 step is 65536). The floor is for a point at the origin alone:
    // an absolute 1e-6 put the camera of a scene 1.6e-8 across (it builds down to ~2e-10) so far
    // back that it showed none of it (a helper's audit).
    const double far_out = std::max({std::fabs(center[0]), std::fabs(center[1]), std::fabs(center[2])});
    const double radius = std::max({norm(sub(hi, lo)) / 2, 1e-30, 1e-5 * far_out});
    D3 direction{0.35, -1.0, 0.7};
    const double n = norm(direction);
    direction = {direction[0] / n, direction[1] / n, direction[2] / n};
    const double fov = kDefaultFovY;
    const double distance = radius / std::sin(fov * (M_PI / 180.0) / 2) * 1.05;  // as Python's math.radians
    return {add_scaled(center, direction, distance), center, {0, 0, 1}, fov};
}

std::array<double, 3> default_light_position(const CameraPlacement& camera) {
    const D3 forward = sub(camera.target, camera.position);
    D3 right = cross(forward, camera.up);
    const double r = norm(right), u = norm(camera.up);
    right = {right[0] / r, right[1] / r, right[2] / r};
    // up as a direction: its length (Camera takes any) moved the light (up ×10: 10× as high)
    const D3 up = {camera.up[0] / u, camera.up[1] / u, camera.up[2] / u};
    const double dist = norm(forward);
    D3 out = camera.position;
    for (int k = 0; k < 3; ++k) out[k] = out[k] + right[k] * 0.3 * dist + up[k] * 0.3 * dist;
    return pulled_within_range(camera.position, out);  // towards the camera, whose side it is on
}

}  // namespace bvhlab
