// render.h — what a frame is made of (scene in GPU layout, camera, light, settings) and the CPU
// reference renderer. The Vulkan renderer (vulkan_renderer.h) reads the same RenderScene and
// FrameParams, and runs the same tracer code (shaders/tracer/*.glsl).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "bvhlab/big_vector.h"
#include "bvhlab/bvh.h"
#include "gpu_types.h"

namespace bvhlab {

/// Pinhole camera; fov_y_degrees is the vertical field of view.
struct Camera {
    Vec3 position{0, -5, 2}, look_at{0, 0, 0}, up{0, 0, 1};
    float fov_y_degrees = 45.0f;
};

struct PointLight {
    Vec3 position{5, -5, 5};
    Vec3 color{1, 1, 1};
    float intensity = 1.0f;
};

/// Per-primitive materials, borrowed from the caller: M×6 floats (r, g, b, reflective,
/// transparent, ior) and one material index per triangle and per sphere.
struct MaterialView {
    const float* materials = nullptr;
    std::size_t material_count = 0;
    const std::int32_t* triangle_material = nullptr;  ///< null: every triangle uses material 0
    const std::int32_t* sphere_material = nullptr;    ///< null: every sphere uses material 0
};

/// The scene as both renderers read it: the tree, the geometry and materials in GPU layout,
/// and every node's box sorted by depth for the overlay (report §3.3.1).
struct RenderScene {
    const Bvh* bvh = nullptr;  ///< borrowed: must outlive the RenderScene
    BigVector<gpu::GpuTriangle> triangles;
    std::vector<gpu::GpuSphere> spheres;
    std::vector<gpu::GpuMaterial> materials;
    BigVector<gpu::GpuBox> boxes;
    std::vector<std::uint32_t> depth_offset;  ///< boxes of depth d: [depth_offset[d], depth_offset[d + 1])
    Aabb bounds;
    std::uint32_t node_count = 0;  ///< of the tree (kept here: make_frame_params never reads `bvh`)

    /// [first, count) of the boxes whose depth lies in [depth_min, depth_max].
    std::pair<std::uint32_t, std::uint32_t> box_range(std::uint32_t depth_min, std::uint32_t depth_max) const;
};

/// Throws std::invalid_argument for material indices out of range or bad material values.
RenderScene make_render_scene(const Bvh& bvh, const GeometryView& geometry, const MaterialView& materials);

enum class RenderMode { Shade, Heatmap };

struct RenderSettings {
    std::uint32_t width = 800, height = 600;
    std::uint32_t samples_per_axis = 1;  ///< n×n supersampling
    std::uint32_t max_depth = 5;         ///< bounces of reflection and refraction
    Camera camera;
    PointLight light;
    Vec3 sky{0.55f, 0.7f, 0.9f};         ///< the atmosphere colour (report §2.1)
    bool overlay = false;                ///< draw the boxes of depths [overlay_depth_min, overlay_depth_max]
    std::uint32_t overlay_depth_min = 0, overlay_depth_max = 0;
    bool overlay_color_by_depth = true;
    float line_width = 1.0f;
    std::uint32_t traversal = gpu::TRAVERSAL_STACK;  ///< or gpu::TRAVERSAL_STACKLESS
    RenderMode mode = RenderMode::Shade;
    float heatmap_scale = 0.0f;          ///< box tests shown as full red; 0 = 8 × tree height
};

/// Throws std::invalid_argument naming the bad setting (size zero or above max_dimension, NaN
/// camera, camera looking along its up vector, too many samples or bounces).
void validate(const RenderSettings& settings, std::uint32_t max_dimension = 16384);

/// The per-frame parameters both renderers read (addresses left zero; the GPU side fills them).
gpu::FrameParams make_frame_params(const RenderScene& scene, const RenderSettings& settings);

struct RenderTimings {
    double upload_ms = 0, overlay_ms = 0, trace_ms = 0, readback_ms = 0, total_ms = 0;
    std::string device;
};

/// The CPU reference renderer: the same tracer code as the compute shader, on `threads` threads
/// (0 = all). Writes width×height RGBA floats, row 0 at the top.
RenderTimings render_cpu(const RenderScene& scene, const RenderSettings& settings, float* rgba,
                         std::uint32_t threads = 0);

}  // namespace bvhlab
