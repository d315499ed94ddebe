// render_settings.h — what a render is asked to do, with documented defaults, the names the Python
// API and the CLI use for its choices, and its limits. Checked once, here (validate).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "bvhlab/camera.h"
#include "bvhlab/render_defaults.h"
#include "bvhlab/traverse.h"
#include "bvhlab/vec3.h"

namespace bvhlab {

struct PointLight {
    Vec3 position{5, -5, 5};
    Vec3 color{1, 1, 1};
    float intensity = 1.0f;
};

enum class RenderMode {
    Shade,    ///< the Whitted image (report §2.1)
    Heatmap,  ///< the box tests of the primary rays as colours, blue (few) to red (heatmap_scale)
};

/// A traversal counter of a pixel (issue 35; the traversal counters of AMD's Radeon Raytracing
/// Analyzer), in gpu_types.h's COUNTER_* order. Counted for each primary ray's closest-hit walk
/// only (reflection, refraction and shadow rays are not), averaged over the pixel's samples.
enum class TraversalCounter {
    BoxTests,      ///< boxes tested (what the heatmap mode colours)
    BoxHits,       ///< boxes the ray entered
    PrimTests,     ///< primitives tested
    PrimHits,      ///< primitive tests that found a hit nearer than the closest so far
    InstanceHits,  ///< two-level scenes: instances entered (TLAS leaves reached); 0 in a flat scene
};

struct RenderSettings {
    std::uint32_t width = 800, height = 600;
    std::uint32_t samples_per_axis = 1;  ///< n: n×n samples per pixel on a regular grid
    std::uint32_t max_ray_depth = 5;     ///< bounces of reflection and refraction (0: primary rays)
    Camera camera;
    PointLight light;
    Vec3 sky = kDefaultSky;  ///< the atmosphere colour (report §2.1)
    bool overlay = false;    ///< draw the boxes of depths [overlay_depth_min, overlay_depth_max]
    std::uint32_t overlay_depth_min = 0, overlay_depth_max = 0;
    bool overlay_color_by_depth = true;  ///< else overlay_color
    /// The overlay's line colour when not by depth: one definition for the tracer's overlay pass
    /// and the add-on's viewport drawing (its colour property's default).
    Vec3 overlay_color = kDefaultOverlayColor;
    float line_width = 1.0f;  ///< pixels (Vulkan devices without wide lines draw 1)
    /// Stack or Stackless (report §3.1); Wide: the CPU tracer answers each query through the CPU
    /// queries' 8-wide trees (the same image, 1.5-3× faster; no traversal_counters; its cost: 8 box
    /// tests a wide node in a flat scene, the two-level query's count in a two-level one), the
    /// Vulkan tracer refuses it
    Traversal traversal = Traversal::Stack;
    RenderMode mode = RenderMode::Shade;
    std::optional<float> heatmap_scale;  ///< box tests shown as full red; unset: 8 × tree height
    /// Keep every TraversalCounter per pixel (RenderImages::counters; 20 more bytes a pixel).
    bool traversal_counters = false;
    /// Keep each pixel's cost (box tests per primary ray: RenderImages::cost and ::heat). Off, the
    /// CPU tracer's wide traversal of a flat scene traces camera rays eight at a time where they
    /// run together (the batch's packets, wide_bvh.h intersect_wide_batch: the same hits, so the
    /// same image), which count no box tests, and the job refuses cost and heat (RenderJob::resolve).
    /// The heatmap mode, whose image the cost is, needs it.
    bool keep_cost = true;
    /// Blender's Film ▸ Transparent: where a camera ray shows nothing the sample adds no colour, and
    /// a pixel's alpha is the share of its samples whose camera ray shows a surface or the overlay's
    /// line (colour premultiplied, as Cycles writes it; 4 more bytes a pixel). Rays after a bounce
    /// still see the sky. The shaded image only: the heatmap stays opaque.
    bool film_transparent = false;
    /// Tracer steps one pixel may run per dispatch (gpu::MIN_STEPS_PER_DISPATCH ..
    /// MAX_STEPS_PER_DISPATCH); unset: chosen by the renderer. Only how the work is cut changes,
    /// never the image.
    std::optional<std::uint32_t> steps_per_dispatch;
    /// A pixel needing more steps of work (a node, a primitive, a pop, a ray's bookkeeping) than this
    /// in one RenderJob::run is an error (RenderIncomplete), the same on both backends; unset: the
    /// most a correct trace of this scene can take (none above 2^32 - 2).
    std::optional<std::uint64_t> max_steps_per_pixel;
};

// Limits, exported to Python so the API, the CLI and the add-on never retype them.
inline constexpr std::uint32_t kMaxImageDimension = 16384;  ///< pixels per side (CPU; Vulkan: the device's)
inline constexpr float kMaxHeatmapScale = 1e6f;             ///< box tests per ray at full red
inline constexpr float kMaxLineWidth = 16.0f;

/// The whole pixels across a line `line_width` wide, as rasterizers draw it (Vulkan's wide lines:
/// the width rounded, half away from zero, lavapipe's roundf; at least 1).
inline float whole_line_width(float line_width) { return std::max(1.0f, std::round(line_width)); }

/// Throws std::invalid_argument when width × height is empty or above max_dimension per side: what
/// validate checks first, for callers that must refuse a size before they allocate for it.
void validate_image_size(std::uint32_t width, std::uint32_t height, std::uint32_t max_dimension = kMaxImageDimension);

/// Throws std::invalid_argument naming the bad setting (size zero or above max_dimension, a bad
/// camera (validate(Camera)), too many samples or bounces, a bad heatmap scale, the box overlay
/// with a panoramic camera).
void validate(const RenderSettings& settings, std::uint32_t max_dimension = kMaxImageDimension);

/// Names as the Python API and the CLI spell them; parse_* throw std::invalid_argument listing
/// the valid names. Traversal names are traverse.h's (the CPU queries know "wide" too).
Traversal parse_traversal(std::string_view name);
RenderMode parse_render_mode(std::string_view name);
TraversalCounter parse_traversal_counter(std::string_view name);
std::string to_string(TraversalCounter counter);
std::vector<std::string> traversal_counter_names();  ///< box_tests, box_hits, prim_tests, prim_hits, instance_hits
std::string to_string(Traversal traversal);
std::string to_string(RenderMode mode);
std::vector<std::string> traversal_names();  ///< every traversal (the queries' and the tracers')
std::vector<std::string> render_mode_names();

/// gpu::TRAVERSAL_STACK / TRAVERSAL_STACKLESS / TRAVERSAL_WIDE (the CPU tracer's) for the tracer.
std::uint32_t gpu_traversal(Traversal traversal);

}  // namespace bvhlab
