// The overlay pass on the CPU (report §3.3): the boxes of a depth range as lines
// frame.overlay_line_width pixels wide with a depth test, the line's point relative to the camera in xyz and its box's depth + 1
// in w (shade.glsl's line_distance, line_color, line_on_surface read them) — what overlay.vert/.frag make the GPU's
// rasterizer do. The projection is the shared overlay_clip(); only clipping and stepping are local.
#include <algorithm>
#include <cmath>

#include "cpu_tracer.h"
#include "overlay_cpu.h"

namespace bvhlab {
namespace {

using gpu::vec3;
using gpu::vec4;

struct Target {
    std::vector<vec4>& color;  // the line's point relative to the camera + its box's depth + 1
    std::vector<float>& depth;
    std::uint32_t width, height;
    int line_width;          // whole pixels across the line, in its minor direction
    gpu::CpuTracer& tracer;  // the shared overlay code (overlay.glsl)

    float distance(vec3 from_camera) { return tracer.overlay_distance(from_camera); }
};

/// A segment between two clip-space points, with the camera-relative positions they project.
struct Segment {
    vec4 a, b;
    vec3 pa, pb;
};

/// Clips the segment to the view volume -w <= x, y <= w, 0 <= z <= w (Liang–Barsky in homogeneous
/// clip space, where a segment stays a segment with the same parameter as in world space); false
/// if nothing is left. Afterwards both ends project inside the image, so stepping is bounded by
/// its size whatever the field of view (issue 8: a tiny fov sent the stepper to ±1e9 pixels).
bool clip_to_view(Segment& s) {
    const vec4 d = s.b - s.a;
    float t0 = 0.0f, t1 = 1.0f;
    // each plane as (value at a, change along the segment); inside where value >= 0
    const float planes[6][2] = {{s.a.w + s.a.x, d.w + d.x},
                                {s.a.w - s.a.x, d.w - d.x},
                                {s.a.w + s.a.y, d.w + d.y},
                                {s.a.w - s.a.y, d.w - d.y},
                                {s.a.z, d.z},
                                {s.a.w - s.a.z, d.w - d.z}};
    for (const auto& [value, change] : planes) {
        if (change == 0.0f) {
            if (!(value >= 0.0f)) return false;
            continue;
        }
        const float t = -value / change;
        if (change > 0.0f) t0 = std::max(t0, t);
        else t1 = std::min(t1, t);
        if (!(t0 <= t1)) return false;
    }
    const vec4 a = s.a + d * t0, b = s.a + d * t1;
    const vec3 pa = s.pa + (s.pb - s.pa) * t0, pb = s.pa + (s.pb - s.pa) * t1;
    s = {a, b, pa, pb};
    return a.w > 0.0f && b.w > 0.0f;
}

/// The columns (rows) whose pixels the segment from `from` to `to` can touch on an axis of
/// `extent` pixels, as [first, last]: those whose pixel's diamond spans part of it.
std::pair<int, int> pixel_span(float from, float to, std::uint32_t extent) {
    const float first = std::max(std::floor(std::min(from, to)), 0.0f);
    const float last = std::min(std::floor(std::max(from, to)), float(extent) - 1.0f);
    if (!(first <= last)) return {0, -1};  // also for NaN
    return {int(first), int(last)};
}

/// Whether (major, minor) lies inside the diamond |x − xf| + |y − yf| < 1/2 of the pixel whose
/// centre is (centre_major, centre_minor): the Vulkan spec's region of the diamond-exit rule.
bool inside_diamond(float major, float minor, float centre_major, float centre_minor) {
    return std::fabs(major - centre_major) + std::fabs(minor - centre_minor) < 0.5f;
}

/// Steps along the major axis a column (row) at a time (a DDA), interpolating the camera-relative
/// position perspective-correctly for the distance (which the lines are depth-tested by:
/// overlay_line_depth), and the clip depth linearly in screen space (outside [0, 1]: not drawn).
/// Which columns: the Vulkan spec's diamond-exit rule for Bresenham lines (its "Bresenham Line
/// Segment Rasterization"): a pixel is drawn where the segment, from its first vertex to its
/// second, leaves the pixel's diamond. For a line at most 45° off its major axis, the column's
/// pixel is the one the line crosses at the column's centre, and the segment meets that pixel's
/// diamond exactly where it reaches the centre line or starts inside the diamond; it leaves it
/// unless it ends inside it. So a segment's first pixel is drawn where it starts inside the
/// diamond even short of the centre, its last left out where it ends inside the diamond past the
/// centre (the centres within the segment took both the other way: 4.6% of the line pixels of a
/// knot's boxes of depths 3-9 at 96×64 apart from lavapipe's). The attributes are those at the
/// column's centre, extrapolated past the segment's end where the pixel lies beyond it, as a
/// rasterizer's interpolation does.
/// At each step the line covers the `line_width` pixels of the minor axis whose centres lie within
/// half the width of it, the one at the far edge left out: lavapipe's Bresenham lines wider than a
/// pixel (a parallelogram that wide in the minor direction, centred on the line; measured against
/// it at widths 2, 3, 4 and 16: whitted 6, 10, 10 and 33 line pixels apart, line ends), and at
/// width 1 the pixel the line crosses, the one before it where the line lies exactly on the edge
/// between two (floor took the one after: a vertical edge at the image's centre moved one pixel
/// against lavapipe; the diamond test alone would draw neither, the spec perturbing such lines
/// off the edge). The Vulkan spec leaves wide Bresenham lines' pixels to the device.
void draw_line(Target& t, Segment s, float depth_key) {
    if (!clip_to_view(s)) return;
    const vec4 a = s.a, b = s.b;
    float ax = (a.x / a.w + 1) * 0.5f * t.width, ay = (a.y / a.w + 1) * 0.5f * t.height;
    float bx = (b.x / b.w + 1) * 0.5f * t.width, by = (b.y / b.w + 1) * 0.5f * t.height;
    float dx = bx - ax, dy = by - ay;
    bool x_major = std::fabs(dx) >= std::fabs(dy);
    const float a_major = x_major ? ax : ay, a_minor = x_major ? ay : ax;
    const float b_major = x_major ? bx : by, b_minor = x_major ? by : bx;
    auto [first, last] = pixel_span(a_major, b_major, x_major ? t.width : t.height);
    float length_major = x_major ? dx : dy;
    if (length_major == 0.0f) return;  // a point leaves no diamond (and a NaN end is no line)
    const float half = 0.5f * float(t.line_width);
    const int minor_extent = int(x_major ? t.height : t.width);
    for (int i = first; i <= last; ++i) {
        const float centre_major = float(i) + 0.5f;
        const float s_major = (centre_major - a_major) / length_major;
        const float centre = x_major ? ay + dy * s_major : ax + dx * s_major;  // where the line crosses
        // the pixel the line crosses: k + 0.5 in [centre − 0.5, centre + 0.5)
        const float crossed = std::ceil(centre - 1.0f) + 0.5f;
        const bool reaches_centre = s_major >= 0.0f && s_major <= 1.0f;
        if (inside_diamond(b_major, b_minor, centre_major, crossed)) continue;  // ends inside: never leaves
        if (!reaches_centre && !inside_diamond(a_major, a_minor, centre_major, crossed)) continue;
        // the pixels k with k + 0.5 in [centre - half, centre + half)
        const float lo = std::max(std::ceil(centre - half - 0.5f), 0.0f);
        const float hi = std::min(std::ceil(centre + half - 0.5f) - 1.0f, float(minor_extent - 1));
        if (!(lo <= hi)) continue;  // off the image (or NaN)
        float depth = (a.z / a.w) * (1 - s_major) + (b.z / b.w) * s_major;
        if (depth < 0 || depth > 1) continue;
        float persp = (s_major / b.w) / ((1 - s_major) / a.w + s_major / b.w);  // screen → world parameter
        vec3 p = s.pa + (s.pb - s.pa) * persp;
        const float distance = t.distance(p);                            // p is relative to the camera
        const float line_depth = t.tracer.overlay_line_depth(distance);  // the GPU's test (overlay.frag)
        for (int minor = int(lo); minor <= int(hi); ++minor) {
            int px = x_major ? i : minor, py = x_major ? minor : i;
            std::size_t k = std::size_t(py) * t.width + std::size_t(px);
            if (!(line_depth < t.depth[k])) continue;  // NaN: not drawn, as the GPU's LESS test
            t.depth[k] = line_depth;
            t.color[k] = vec4(p, depth_key);  // the line's point at this column: line_on_surface
        }
    }
}

}  // namespace

std::vector<gpu::vec4> rasterize_overlay(const RenderScene& scene, const gpu::FrameParams& frame) {
    const std::size_t pixels = std::size_t(frame.width) * frame.height;
    std::vector<vec4> color(pixels, vec4(0.0f));
    if (!frame.overlay_enabled) return color;
    std::vector<float> depth(pixels, 2.0f);
    gpu::CpuTracer tracer(scene, frame, nullptr, nullptr, gpu::TRAVERSAL_STACK);
    Target target{color, depth, frame.width, frame.height, int(frame.overlay_line_width), tracer};
    // distances are measured from the camera: work relative to it
    const vec3 cam = frame.camera_position;
    for (std::uint32_t b = frame.overlay_first_box; b < frame.overlay_last_box; ++b) {
        const gpu::GpuBox& box = scene.boxes[b];
        vec3 lo = gpu::xyz(box.lo_depth), hi = gpu::xyz(box.hi);
        const float depth_key = float(gpu::uint(box.lo_depth.w) + 1u);  // as overlay.frag's
        for (gpu::uint v = 0; v < 24; v += 2) {
            vec3 pa = tracer.corner_position(lo, hi, tracer.box_corner(v));
            vec3 pb = tracer.corner_position(lo, hi, tracer.box_corner(v + 1));
            draw_line(target, {tracer.overlay_clip(pa), tracer.overlay_clip(pb), pa - cam, pb - cam}, depth_key);
        }
    }
    return color;
}

}  // namespace bvhlab
