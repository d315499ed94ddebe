// The cameras (camera.h): their checks and names, and the frame parameters the tracer's camera_ray
// (shaders/tracer/camera.glsl) reads. The view plane follows Cycles' blender_camera_viewplane
// (intern/cycles/blender/camera.cpp), the panoramic ranges Cycles' Camera::update
// (intern/cycles/scene/camera.cpp: equirectangular_range).
#include "../platform/number_text.h"
#include "bvhlab/coordinate_range.h"
#include "camera_frame.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>

namespace bvhlab {
namespace {

constexpr std::array<std::pair<std::string_view, Projection>, 4> kProjections{{
    {"perspective", Projection::Perspective},
    {"orthographic", Projection::Orthographic},
    {"equirectangular", Projection::Equirectangular},
    {"fisheye", Projection::FisheyeEquidistant},
}};
static_assert(std::uint32_t(Projection::Perspective) == gpu::PROJECTION_PERSPECTIVE &&
              std::uint32_t(Projection::Orthographic) == gpu::PROJECTION_ORTHOGRAPHIC &&
              std::uint32_t(Projection::Equirectangular) == gpu::PROJECTION_EQUIRECTANGULAR &&
              std::uint32_t(Projection::FisheyeEquidistant) == gpu::PROJECTION_FISHEYE_EQUIDISTANT);

constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void fail(const std::string& msg) { throw std::invalid_argument(msg); }

double radians(double degrees) { return degrees * (kPi / 180.0); }

bool all_values_finite(const Camera& c) {
    const float values[] = {c.fov_y_degrees,   c.ortho_scale,    c.aspect,
                            c.shift_x,         c.shift_y,        c.clip_start,
                            c.aperture_radius, c.focus_distance, c.fisheye_fov_degrees,
                            c.latitude_min,    c.latitude_max,   c.longitude_min,
                            c.longitude_max,   c.region[0],      c.region[1],
                            c.region[2],       c.region[3]};
    return all_finite(c.position) && all_finite(c.forward) && all_finite(c.up) &&
           std::all_of(std::begin(values), std::end(values), [](float v) { return std::isfinite(v); });
}

/// Blender's largest fisheye field of view (its RNA's hard bound, 10π), and a bound on longitudes
/// (Blender sets none) within which float32 keeps a tenth of a degree.
constexpr double kMaxFisheyeDegrees = 1800, kMaxLongitude = 1e5;

void validate_projection(const Camera& c) {
    switch (c.projection) {
        case Projection::Perspective:
            if (!(c.fov_y_degrees > 0 && c.fov_y_degrees < 180)) fail("camera fov_y must be in (0, 180) degrees");
            break;
        case Projection::Orthographic:
            if (!(c.ortho_scale > 0)) fail("an orthographic camera needs ortho_scale > 0 (the view's larger side)");
            break;
        // The panoramas take what Blender's camera settings take and Cycles renders (a probe,
        // 2026-12-07): a field of view past 360 degrees (the angle from the axis keeps growing to
        // the ellipse's edge, up to Blender's 1800), a range from its max to its min (the image
        // mirrored), or of no extent, and longitudes past ±180 (the directions wrap around).
        case Projection::FisheyeEquidistant:
            if (!(c.fisheye_fov_degrees > 0 && c.fisheye_fov_degrees <= kMaxFisheyeDegrees))
                fail("camera fisheye_fov must be in (0, 1800] degrees");
            break;
        case Projection::Equirectangular:
            if (!(std::fabs(c.latitude_min) <= 90 && std::fabs(c.latitude_max) <= 90))
                fail("camera latitude must be within [-90, 90] degrees");
            if (!(std::fabs(c.longitude_min) <= kMaxLongitude && std::fabs(c.longitude_max) <= kMaxLongitude))
                fail("camera longitude must be within ±100,000 degrees");
            break;
        default:
            fail("unknown camera projection " + std::to_string(std::uint32_t(c.projection)));
    }
}

constexpr float kMinAspect = 1e-8f, kMaxShift = 1000.0f;

void validate_lens(const Camera& c) {
    if (!(c.clip_start >= 0 && c.clip_end > c.clip_start))
        fail("camera clipping must be 0 <= clip_start < clip_end, got " + number_text(c.clip_start) + ", " +
             number_text(c.clip_end));
    if (c.aperture_radius < 0) fail("camera aperture_radius must be >= 0 (0: no depth of field)");
    // the lens's points are ray origins: within the coordinate range, as the position is (an
    // aperture of 1e20 was taken and rendered black: an audit)
    const double lens_reach =
        std::max({std::fabs(double(c.position.x)), std::fabs(double(c.position.y)), std::fabs(double(c.position.z))}) +
        double(c.aperture_radius);
    if (!(lens_reach <= double(kMaxCoordinate)))
        fail("camera aperture_radius must keep the lens within the coordinate range ±2^40 (" +
             number_text(kMaxCoordinate) + "), got " + number_text(c.aperture_radius));
    // within what float32 rays hold: an aspect of 1e20 or a shift of -1e20 overflowed the ray
    // directions to inf, and half the image or all of it came out black. Blender's widest frame
    // (65,536 × 4 pixels at a pixel aspect of 200) is 3.3e6 wide; its shifts are within ±10.
    if (c.aspect != 0 && !(c.aspect >= kMinAspect && c.aspect <= 1 / kMinAspect))
        fail("camera aspect must be between 1e-8 and 1e8 (or 0: the image's), got " + number_text(c.aspect));
    if (!(std::fabs(c.shift_x) <= kMaxShift && std::fabs(c.shift_y) <= kMaxShift))
        fail("camera lens shift must be within ±1000 (fractions of the image plane), got " + number_text(c.shift_x) +
             ", " + number_text(c.shift_y));
    if (c.aperture_radius > 0 && !(c.focus_distance > 0)) fail("camera focus_distance must be > 0");
    const auto& r = c.region;
    if (!(r[0] >= 0 && r[0] < r[2] && r[2] <= 1 && r[1] >= 0 && r[1] < r[3] && r[3] <= 1))
        fail("camera region must be x0 < x1 and y0 < y1 within [0, 1] (fractions of the frame)");
}

/// The frame's rectangle in screen coordinates: left, top edges and extents (y grows upwards).
struct Window {
    double left, top, width, height;
};

Window frame_window(const Camera& c, double aspect) {
    double width = 1, height = 1, larger = 1, cx = 0.5, cy = 0.5;  // panoramic: Cycles' [0, 1]² plane
    if (c.projection == Projection::Perspective) {
        height = 2 * std::tan(radians(c.fov_y_degrees) / 2);
        width = height * aspect;
        larger = std::max(width, height), cx = 0, cy = 0;
    } else if (c.projection == Projection::Orthographic) {
        larger = c.ortho_scale, cx = 0, cy = 0;
        width = aspect >= 1 ? larger : larger * aspect;
        height = aspect >= 1 ? larger / aspect : larger;
    }
    cx += c.shift_x * larger, cy += c.shift_y * larger;
    return {cx - width / 2, cy + height / 2, width, height};
}

}  // namespace

Vec3 unit(Vec3 v) {
    // In double precision: a float vector's squared length neither overflows nor underflows there,
    // denormal components included (issue 39: a float32 rescale by 1 / max |component| overflowed
    // to inf for a denormal vector, and the camera looked nowhere).
    const double x = v.x, y = v.y, z = v.z;
    const double n = std::sqrt(x * x + y * y + z * z);
    return n > 0 ? Vec3{float(x / n), float(y / n), float(z / n)} : Vec3{};
}

Camera look_at(Vec3 position, Vec3 target, Vec3 up, float fov_y_degrees) {
    Camera c;
    c.position = position;
    c.forward = target - position;
    c.up = up;
    c.fov_y_degrees = fov_y_degrees;
    return c;
}

void validate(const Camera& c) {
    if (!all_values_finite(c) || std::isnan(c.clip_end)) fail("the camera has a NaN or infinite value");
    if (c.aspect < 0) fail("camera aspect must be positive (or 0: the image's)");
    if (c.forward.x == 0 && c.forward.y == 0 && c.forward.z == 0)
        fail("the camera's view direction is zero (position and look_at coincide)");
    if (length(cross(unit(c.forward), unit(c.up))) == 0) fail("camera up is parallel to the viewing direction");
    validate_projection(c);
    validate_lens(c);
}

Projection parse_projection(std::string_view name) {
    std::string names;
    for (const auto& [key, value] : kProjections) {
        if (key == name) return value;
        names.append(" ").append(key);
    }
    fail("unknown projection '" + std::string(name) + "'; expected one of:" + names);
}

std::string to_string(Projection projection) {
    for (const auto& [key, value] : kProjections)
        if (value == projection) return std::string(key);
    return "?";
}

std::vector<std::string> projection_names() {
    std::vector<std::string> out;
    for (const auto& entry : kProjections) out.emplace_back(entry.first);
    return out;
}

void set_camera_frame(gpu::FrameParams& f, const Camera& c, std::uint32_t width, std::uint32_t height) {
    const Vec3 forward = unit(c.forward);
    const Vec3 right = unit(cross(forward, unit(c.up)));
    f.projection = std::uint32_t(c.projection);
    f.camera_position = {c.position.x, c.position.y, c.position.z};
    f.camera_forward = {forward.x, forward.y, forward.z};
    const Vec3 across = c.mirrored ? Vec3{-right.x, -right.y, -right.z} : right;
    f.camera_right = {across.x, across.y, across.z};
    const Vec3 up = cross(right, forward);
    f.camera_up = {up.x, up.y, up.z};
    f.clip_start = c.clip_start;
    f.clip_end = c.clip_end;
    f.aperture_radius = c.aperture_radius;
    f.focus_distance = c.focus_distance;
    // The image shows region [x0, x1] × [y0, y1] of the frame: the frame is wider than the image
    // by 1 / (x1 - x0) and higher by 1 / (y1 - y0).
    const auto& r = c.region;
    const double region_w = double(r[2]) - r[0], region_h = double(r[3]) - r[1];
    const double aspect = c.aspect > 0 ? c.aspect : (double(width) / region_w) / (double(height) / region_h);
    const Window w = frame_window(c, aspect);
    f.screen = {float(w.left + r[0] * w.width), float(w.top - r[1] * w.height), float(region_w * w.width / width),
                float(-region_h * w.height / height)};
    if (c.projection == Projection::Equirectangular)
        f.panorama = {float(radians(double(c.longitude_min) - c.longitude_max)), float(-radians(c.longitude_min)),
                      float(radians(double(c.latitude_min) - c.latitude_max)),
                      float(kPi / 2 - radians(c.latitude_min))};
    else f.panorama = {float(radians(c.fisheye_fov_degrees)), 0, 0, 0};
}

}  // namespace bvhlab
