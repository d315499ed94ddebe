// The overlay pass on the CPU (report §3.3): the boxes of a depth range as 1-pixel lines with a
// depth test, colour in rgb and camera distance in alpha — what overlay.vert/.frag make the GPU's
// rasterizer do. The projection is the shared overlay_clip(); only the line stepping is local.
#include <cmath>

#include "cpu_tracer.h"
#include "overlay_cpu.h"

namespace bvhlab {
namespace {

using gpu::vec3;
using gpu::vec4;

struct Target {
    std::vector<vec4>& color;  // rgb + distance
    std::vector<float>& depth;
    std::uint32_t width, height;
};

/// Clips the segment a–b (clip space) to the near plane z >= 0; false if nothing is left.
bool clip_near(vec4& a, vec4& b, vec3& pa, vec3& pb) {
    if (a.z < 0 && b.z < 0) return false;
    if (a.z >= 0 && b.z >= 0) return true;
    float t = a.z / (a.z - b.z);
    vec4 m = a + (b - a) * t;
    vec3 pm = pa + (pb - pa) * t;
    if (a.z < 0) a = m, pa = pm;
    else b = m, pb = pm;
    return true;
}

/// Steps along the major axis through pixel centres (a DDA), interpolating the camera-relative
/// position perspective-correctly for the distance, and depth linearly in screen space.
void draw_line(Target& t, vec4 a, vec4 b, vec3 pa, vec3 pb, vec3 color) {
    if (!clip_near(a, b, pa, pb) || a.w <= 0 || b.w <= 0) return;
    float ax = (a.x / a.w + 1) * 0.5f * t.width, ay = (a.y / a.w + 1) * 0.5f * t.height;
    float bx = (b.x / b.w + 1) * 0.5f * t.width, by = (b.y / b.w + 1) * 0.5f * t.height;
    float dx = bx - ax, dy = by - ay;
    bool x_major = std::fabs(dx) >= std::fabs(dy);
    float from = x_major ? std::min(ax, bx) : std::min(ay, by), to = x_major ? std::max(ax, bx) : std::max(ay, by);
    int first = int(std::ceil(from - 0.5f)), last = int(std::floor(to - 0.5f));
    float length_major = x_major ? dx : dy;
    for (int i = first; i <= last; ++i) {
        float s = length_major != 0 ? ((float(i) + 0.5f) - (x_major ? ax : ay)) / length_major : 0.0f;
        s = std::clamp(s, 0.0f, 1.0f);
        float minor = x_major ? ay + dy * s : ax + dx * s;
        int px = x_major ? i : int(std::floor(minor)), py = x_major ? int(std::floor(minor)) : i;
        if (px < 0 || py < 0 || px >= int(t.width) || py >= int(t.height)) continue;
        float depth = (a.z / a.w) * (1 - s) + (b.z / b.w) * s;
        float persp = (s / b.w) / ((1 - s) / a.w + s / b.w);  // screen → world parameter
        vec3 p = pa + (pb - pa) * persp;
        std::size_t k = std::size_t(py) * t.width + std::size_t(px);
        if (depth < 0 || depth > 1 || depth >= t.depth[k]) continue;
        t.depth[k] = depth;
        t.color[k] = vec4(color, gpu::length(p));  // p is relative to the camera
    }
}

}  // namespace

std::vector<gpu::vec4> rasterize_overlay(const RenderScene& scene, const RenderSettings& settings,
                                         const gpu::FrameParams& frame) {
    const std::size_t pixels = std::size_t(settings.width) * settings.height;
    std::vector<vec4> color(pixels, vec4(0.0f));
    if (!frame.flags.y || frame.overlay_range.y == 0) return color;
    std::vector<float> depth(pixels, 2.0f);
    gpu::CpuTracer tracer(scene, frame, nullptr, gpu::TRAVERSAL_STACK);
    Target target{color, depth, settings.width, settings.height};
    // distances are measured from the camera: work relative to it
    const vec3 cam = gpu::xyz(frame.camera_position);
    for (std::uint32_t b = frame.overlay_range.x; b < frame.overlay_range.x + frame.overlay_range.y; ++b) {
        const gpu::GpuBox& box = scene.boxes[b];
        vec3 lo = gpu::xyz(box.lo_depth), hi = gpu::xyz(box.hi);
        vec3 line_color = frame.overlay_range.z ? tracer.depth_color(gpu::uint(box.lo_depth.w)) : vec3(1.0f, 0.85f, 0.2f);
        for (gpu::uint v = 0; v < 24; v += 2) {
            vec3 pa = tracer.corner_position(lo, hi, tracer.box_corner(v));
            vec3 pb = tracer.corner_position(lo, hi, tracer.box_corner(v + 1));
            draw_line(target, tracer.overlay_clip(pa), tracer.overlay_clip(pb), pa - cam, pb - cam, line_color);
        }
    }
    return color;
}

}  // namespace bvhlab
