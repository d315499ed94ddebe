// The scene in GPU layout and the per-frame parameters: everything both renderers share before any
// tracing happens.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "bvhlab/render.h"
#include "camera_frame.h"
#include "render_scene_parts.h"

namespace bvhlab {
namespace {

gpu::vec3 v3(Vec3 v) { return {v.x, v.y, v.z}; }

}  // namespace

namespace render_parts {

gpu::vec4 v4(Vec3 v, float w) { return {v.x, v.y, v.z, w}; }

std::uint32_t material_index(const std::int32_t* table, std::size_t i, std::size_t count, const char* what) {
    std::int32_t m = table ? table[i] : 0;
    if (m < 0 || std::size_t(m) >= count)
        throw std::invalid_argument(std::string(what) + " " + std::to_string(i) + " uses material " +
                                    std::to_string(m) + " of " + std::to_string(count));
    return std::uint32_t(m);
}

namespace {
template <class T>
gpu::GpuMaterial gpu_material(const T* m) {
    return {{float(m[0]), float(m[1]), float(m[2]), float(m[3])}, {float(m[4]), float(m[5]), float(m[6]), float(m[7])}};
}

}  // namespace

std::vector<gpu::GpuMaterial> gpu_materials(const MaterialView& mv) {
    std::vector<gpu::GpuMaterial> out;
    for (std::size_t i = 0; i < mv.material_count; ++i) {
        const float* m = mv.materials + kMaterialFloats * i;
        for (std::size_t k = 0; k < kMaterialFloats; ++k)
            if (!std::isfinite(m[k])) throw std::invalid_argument("material " + std::to_string(i) + " has a NaN value");
        if (m[3] < 0 || m[3] > 1 || m[4] < 0 || m[4] > 1 || m[5] <= 0)
            throw std::invalid_argument("material " + std::to_string(i) +
                                        ": reflective and transparent must be in [0, 1] and ior > 0");
        if (m[6] != 0 && m[6] != 1)
            throw std::invalid_argument("material " + std::to_string(i) + ": holdout must be 0 or 1");
        if (!(m[7] >= 0 && m[7] <= float(gpu::RAY_KINDS)) || m[7] != std::floor(m[7]))
            throw std::invalid_argument("material " + std::to_string(i) + ": hidden must be a whole number in [0, " +
                                        std::to_string(gpu::RAY_KINDS) + "] (RAY_* bits)");
        out.push_back(gpu_material(m));
    }
    if (out.empty()) out.push_back(gpu_material(kDefaultMaterial.data()));
    return out;
}

bool any_holdout(const std::vector<gpu::GpuMaterial>& materials) {
    return std::any_of(materials.begin(), materials.end(),
                       [](const gpu::GpuMaterial& m) { return m.transparent_ior.z != 0.0f; });
}

bool any_hidden(const std::vector<gpu::GpuMaterial>& materials) {
    return std::any_of(materials.begin(), materials.end(),
                       [](const gpu::GpuMaterial& m) { return m.transparent_ior.w != 0.0f; });
}

void check_tree_matches(const Bvh& bvh, const GeometryView& g) {
    // the TLAS of a two-level tree as a tree: its references are instances (over a scene without
    // primitives its counts matched, 0 and 0, and the tracer read instances as primitives: a crash)
    if (bvh.prims.size() != bvh.refs.size())
        throw std::invalid_argument(
            "this tree holds no geometry (the TLAS of a two-level tree, whose references are instances): "
            "render the InstancedBvh");
    if (g.triangle_count != bvh.triangle_count || g.sphere_count != bvh.sphere_count)
        throw std::invalid_argument("the geometry does not match the tree (different primitive counts)");
    if (geometry_fingerprint(g) != bvh.fingerprint())
        throw std::invalid_argument(
            "the tree was built for other geometry (same counts, different coordinates): "
            "build it again, or refit it, for these triangles and spheres");
}

/// The boxes of the overlay pass, in the depth order (report §3.3.1).
void fill_boxes(RenderScene& s, const Bvh& bvh) {
    s.order = make_depth_order(bvh);
    s.tree_height = s.order.height();
    s.boxes.resize(s.order.nodes.size());
    for (std::size_t k = 0; k < s.order.nodes.size(); ++k) {
        const BvhNode& n = bvh.nodes[s.order.nodes[k]];
        s.boxes[k] = {{n.lo.x, n.lo.y, n.lo.z, float(bvh.depths[s.order.nodes[k]])}, {n.hi.x, n.hi.y, n.hi.z, 0}};
    }
}

}  // namespace render_parts

using namespace render_parts;

RenderScene make_render_scene(const Bvh& bvh, const GeometryView& g, const MaterialView& mv) {
    check_tree_matches(bvh, g);
    RenderScene s;
    s.bvh = &bvh;
    s.materials = gpu_materials(mv);
    s.holdout = any_holdout(s.materials);
    s.hidden = any_hidden(s.materials);
    const std::size_t n_materials = mv.material_count ? mv.material_count : 1;
    s.triangles.resize(g.triangle_count);
    for (std::size_t i = 0; i < g.triangle_count; ++i)
        s.triangles[i] = pack_triangle(g, i, material_index(mv.triangle_material, i, n_materials, "triangle"));
    s.spheres.resize(g.sphere_count);
    for (std::size_t i = 0; i < g.sphere_count; ++i) {
        std::uint32_t m = material_index(mv.sphere_material, i, n_materials, "sphere");
        s.spheres[i] = {v4(g.sphere_center(i), g.sphere_radius(i)), {m, 0, 0, 0}};
    }
    fill_boxes(s, bvh);
    s.pairs = make_pair_nodes(bvh);
    if (!bvh.empty()) s.bounds = node_box(bvh.nodes[0]);
    s.node_count = bvh.node_count();
    s.ref_count = static_cast<std::uint32_t>(bvh.refs.size());
    s.tree_fingerprint = bvh.fingerprint();
    s.stack_entries = std::max(s.height(), 2u) - 1;
    s.walk_steps = 2ull * s.node_count + s.ref_count + 2;
    return s;
}

void set_overlay_boxes(RenderScene& scene, const float* lo, const float* hi, const std::uint8_t* depth,
                       std::size_t count) {
    for (std::size_t k = 1; k < count; ++k)
        if (depth[k] < depth[k - 1])
            throw std::invalid_argument("overlay boxes must be sorted by depth (box " + std::to_string(k) + ")");
    BigVector<gpu::GpuBox> boxes(count);
    std::vector<std::uint32_t> offset(count ? std::size_t(depth[count - 1]) + 2 : 1, 0);  // by depth, as DepthOrder
    for (std::size_t k = 0; k < count; ++k) {
        const float* a = lo + 3 * k;
        const float* b = hi + 3 * k;
        for (int c = 0; c < 3; ++c)
            if (!std::isfinite(a[c]) || !std::isfinite(b[c]) || a[c] > b[c])
                throw std::invalid_argument("overlay box " + std::to_string(k) +
                                            " is not a box (a coordinate is not finite, or lo > hi)");
        ++offset[std::size_t(depth[k]) + 1];
        boxes[k] = {{a[0], a[1], a[2], float(depth[k])}, {b[0], b[1], b[2], 0}};
    }
    for (std::size_t d = 1; d < offset.size(); ++d) offset[d] += offset[d - 1];
    scene.boxes = std::move(boxes);
    scene.order.nodes.clear();  // not node indices: the boxes are given
    scene.order.offset = std::move(offset);
}

void check_render_scene(const RenderScene& scene) {
    if (scene.bvh &&
        (scene.bvh->fingerprint() != scene.tree_fingerprint || scene.bvh->node_count() != scene.node_count))
        throw std::invalid_argument(
            "the tree changed (refit) after its render scene was made: make the render scene again");
    if (!scene.two_level() && scene.node_count > 1 && scene.pairs.size() != scene.node_count / 2)
        throw std::invalid_argument("the render scene has no pairs for its tree's internal nodes (make_render_scene)");
}

float heatmap_scale(const RenderScene& scene, const RenderSettings& s) {
    return s.heatmap_scale ? *s.heatmap_scale : float(std::max<std::uint32_t>(8 * scene.height(), 8));
}

gpu::FrameParams make_frame_params(const RenderScene& scene, const RenderSettings& s) {
    gpu::FrameParams f{};
    set_camera_frame(f, s.camera, s.width, s.height);
    // the overlay's depth range scales with the scene (ray offsets are each hit point's own:
    // shaders/tracer/ray_offset.glsl)
    Aabb b = scene.bounds;
    if (b.empty()) b.grow(s.camera.position + unit(s.camera.forward));
    Vec3 far_corner = max(abs3(b.lo - s.camera.position), abs3(b.hi - s.camera.position));
    float diagonal = std::max(length(b.extent()), 1e-6f);
    // The overlay's depth range: the scene's, within the camera's clipping (a perspective projection
    // needs a near plane in front of the camera; an orthographic one starts at clip_start).
    const float scene_near = std::max(1e-3f * diagonal, 1e-6f);
    f.overlay_near = s.camera.projection == Projection::Perspective ? std::max(scene_near, s.camera.clip_start)
                                                                    : s.camera.clip_start;
    f.overlay_far = std::min(2.0f * length(far_corner) + diagonal, s.camera.clip_end);
    if (!(f.overlay_far > f.overlay_near)) f.overlay_far = 2.0f * f.overlay_near + 1.0f;  // nothing in range
    f.light_position = v3(s.light.position);
    f.light_color = v3(s.light.color * s.light.intensity);
    f.sky = v3(s.sky);
    f.heatmap_scale = heatmap_scale(scene, s);
    f.width = s.width;
    f.height = s.height;
    f.samples_per_axis = s.samples_per_axis;
    f.max_ray_depth = s.max_ray_depth;
    f.mode = s.mode == RenderMode::Heatmap ? gpu::MODE_HEATMAP : gpu::MODE_SHADE;
    f.node_count = scene.node_count;
    auto [first, last] = scene.order.range(s.overlay_depth_min, s.overlay_depth_max);
    f.overlay_enabled = s.overlay && last > first ? 1u : 0u;
    f.overlay_color_by_depth = s.overlay_color_by_depth ? 1u : 0u;
    f.overlay_color = gpu::vec4(v3(s.overlay_color), 1.0f);
    f.overlay_first_box = first;
    f.overlay_last_box = s.overlay ? last : first;
    f.overlay_line_width = whole_line_width(s.line_width);
    f.ray_stack_entries = s.max_ray_depth + 1;
    f.max_work_per_pixel = gpu::NO_WORK_CAP;  // set per run (pixel_sums.h work_cap)
    f.node_stack_entries = std::max(scene.stack_entries, 1u);
    f.instance_count = std::uint32_t(scene.instances.size());
    f.count_traversal = s.traversal_counters ? 1u : 0u;
    f.film_transparent = s.film_transparent ? 1u : 0u;
    f.count_covered = s.film_transparent || scene.holdout ? 1u : 0u;
    f.hidden_materials = scene.hidden ? 1u : 0u;
    return f;
}

}  // namespace bvhlab
