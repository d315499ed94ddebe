// The scene in GPU layout, the settings checks, and the per-frame parameters: everything both
// renderers share before any tracing happens.
#include <cmath>
#include <stdexcept>
#include <string>

#include "bvhlab/depth_order.h"
#include "bvhlab/render.h"

namespace bvhlab {
namespace {

gpu::vec4 v4(Vec3 v, float w) { return {v.x, v.y, v.z, w}; }

std::uint32_t material_index(const std::int32_t* table, std::size_t i, std::size_t count, const char* what) {
    std::int32_t m = table ? table[i] : 0;
    if (m < 0 || std::size_t(m) >= count)
        throw std::invalid_argument(std::string(what) + " " + std::to_string(i) + " uses material " + std::to_string(m) +
                                    " of " + std::to_string(count));
    return std::uint32_t(m);
}

std::vector<gpu::GpuMaterial> gpu_materials(const MaterialView& mv) {
    std::vector<gpu::GpuMaterial> out;
    for (std::size_t i = 0; i < mv.material_count; ++i) {
        const float* m = mv.materials + 6 * i;
        for (int k = 0; k < 6; ++k)
            if (!std::isfinite(m[k])) throw std::invalid_argument("material " + std::to_string(i) + " has a NaN value");
        if (m[3] < 0 || m[3] > 1 || m[4] < 0 || m[4] > 1 || m[5] <= 0)
            throw std::invalid_argument("material " + std::to_string(i) +
                                        ": reflective and transparent must be in [0, 1] and ior > 0");
        out.push_back({{m[0], m[1], m[2], m[3]}, {m[4], m[5], 0, 0}});
    }
    if (out.empty()) out.push_back({{0.8f, 0.8f, 0.8f, 0}, {0, 1.5f, 0, 0}});  // matte white
    return out;
}

}  // namespace

RenderScene make_render_scene(const Bvh& bvh, const GeometryView& g, const MaterialView& mv) {
    if (g.triangle_count != bvh.triangle_count || g.sphere_count != bvh.sphere_count)
        throw std::invalid_argument("the geometry does not match the tree (different primitive counts)");
    if (geometry_fingerprint(g) != bvh.geometry_fingerprint)
        throw std::invalid_argument("the tree was built for other geometry (same counts, different coordinates): "
                                    "build it again, or refit it, for these triangles and spheres");
    RenderScene s;
    s.bvh = &bvh;
    s.materials = gpu_materials(mv);
    const std::size_t n_materials = mv.material_count ? mv.material_count : 1;
    s.triangles.resize(g.triangle_count);
    for (std::size_t i = 0; i < g.triangle_count; ++i) {
        Vec3 v0 = g.vertex(i, 0), e1 = g.vertex(i, 1) - v0, e2 = g.vertex(i, 2) - v0;
        Vec3 n = cross(e1, e2);
        if (n.x == 0 && n.y == 0 && n.z == 0) e1 = e2 = Vec3{};  // zero area: never hit
        std::uint32_t m = material_index(mv.triangle_material, i, n_materials, "triangle");
        s.triangles[i] = {v4(v0, gpu::uintBitsToFloat(m)), v4(e1, 0), v4(e2, 0)};
    }
    s.spheres.resize(g.sphere_count);
    for (std::size_t i = 0; i < g.sphere_count; ++i) {
        std::uint32_t m = material_index(mv.sphere_material, i, n_materials, "sphere");
        s.spheres[i] = {v4(g.sphere_center(i), g.sphere_radius(i)), {m, 0, 0, 0}};
    }
    DepthOrder order = make_depth_order(bvh);
    s.depth_offset = order.offset;
    s.boxes.resize(order.nodes.size());
    for (std::size_t k = 0; k < order.nodes.size(); ++k) {
        const BvhNode& n = bvh.nodes[order.nodes[k]];
        s.boxes[k] = {{n.lo.x, n.lo.y, n.lo.z, float(bvh.depths[order.nodes[k]])}, {n.hi.x, n.hi.y, n.hi.z, 0}};
    }
    if (!bvh.empty()) s.bounds = node_box(bvh.nodes[0]);
    s.node_count = bvh.node_count();
    return s;
}

std::pair<std::uint32_t, std::uint32_t> RenderScene::box_range(std::uint32_t depth_min, std::uint32_t depth_max) const {
    const auto levels = static_cast<std::uint32_t>(depth_offset.size()) - 1;
    if (depth_offset.size() < 2 || depth_min > depth_max || depth_min >= levels) return {0, 0};
    depth_max = std::min(depth_max, levels - 1);
    return {depth_offset[depth_min], depth_offset[depth_max + 1] - depth_offset[depth_min]};
}

void validate(const RenderSettings& s, std::uint32_t max_dimension) {
    auto fail = [](const std::string& msg) { throw std::invalid_argument(msg); };
    if (s.width == 0 || s.height == 0) fail("image size must be positive, got " + std::to_string(s.width) + "x" + std::to_string(s.height));
    if (s.width > max_dimension || s.height > max_dimension)
        fail("image size " + std::to_string(s.width) + "x" + std::to_string(s.height) + " exceeds the device limit of " +
             std::to_string(max_dimension) + " pixels per side");
    if (s.samples_per_axis < 1 || s.samples_per_axis > gpu::MAX_SAMPLES_PER_AXIS)
        fail("samples per pixel axis must be 1.." + std::to_string(gpu::MAX_SAMPLES_PER_AXIS));
    if (s.max_depth > gpu::MAX_RAY_DEPTH) fail("max_depth must be at most " + std::to_string(gpu::MAX_RAY_DEPTH));
    const Camera& c = s.camera;
    if (!all_finite(c.position) || !all_finite(c.look_at) || !all_finite(c.up) || !std::isfinite(c.fov_y_degrees))
        fail("the camera has a NaN or infinite value");
    if (!(c.fov_y_degrees > 0 && c.fov_y_degrees < 180)) fail("camera fov_y must be in (0, 180) degrees");
    Vec3 forward = c.look_at - c.position;
    if (length(forward) == 0) fail("camera position and look_at coincide");
    if (length(cross(forward, c.up)) == 0) fail("camera up is parallel to the viewing direction");
    if (!all_finite(s.light.position) || !all_finite(s.light.color) || !std::isfinite(s.light.intensity))
        fail("the light has a NaN or infinite value");
    if (!all_finite(s.sky)) fail("the sky colour has a NaN or infinite value");
    if (s.traversal > gpu::TRAVERSAL_STACKLESS) fail("unknown traversal");
    if (!(s.line_width >= 1.0f && s.line_width <= 16.0f)) fail("line_width must be in [1, 16]");
}

gpu::FrameParams make_frame_params(const RenderScene& scene, const RenderSettings& s) {
    const Camera& c = s.camera;
    Vec3 forward = normalize(c.look_at - c.position);
    Vec3 right = normalize(cross(forward, c.up));
    Vec3 up = cross(right, forward);
    float tan_half = std::tan(c.fov_y_degrees * 3.14159265358979f / 360.0f);
    float aspect = float(s.width) / float(s.height);
    // ray offsets and the overlay's depth range scale with the scene
    Aabb b = scene.bounds;
    if (b.empty()) b.grow(c.look_at);
    Vec3 far_corner = max(abs3(b.lo - c.position), abs3(b.hi - c.position));
    float diagonal = std::max(length(b.extent()), 1e-6f);
    float far = 2.0f * length(far_corner) + diagonal;
    float eps = 1e-4f * diagonal;

    gpu::FrameParams f{};
    f.camera_position = v4(c.position, tan_half);
    f.camera_forward = v4(forward, aspect);
    f.camera_right = v4(right, 0);
    f.camera_up = v4(up, 0);
    f.light_position = v4(s.light.position, 1);
    f.light_color = v4(s.light.color * s.light.intensity, 1);
    f.sky = v4(s.sky, 1);
    f.size = {s.width, s.height, s.samples_per_axis, s.max_depth};
    auto height = std::uint32_t(scene.depth_offset.empty() ? 0 : scene.depth_offset.size() - 1);
    float heat = s.heatmap_scale > 0 ? s.heatmap_scale : float(std::max<std::uint32_t>(8 * height, 8));
    f.flags = {s.mode == RenderMode::Heatmap ? gpu::MODE_HEATMAP : gpu::MODE_SHADE, s.overlay ? 1u : 0u,
               scene.node_count, std::uint32_t(heat)};
    f.scale = {eps, std::max(1e-3f * diagonal, 1e-6f), far, 0};
    auto [first, count] = scene.box_range(s.overlay_depth_min, s.overlay_depth_max);
    f.overlay_range = {first, s.overlay ? count : 0u, s.overlay_color_by_depth ? 1u : 0u, 0};
    return f;
}

}  // namespace bvhlab
