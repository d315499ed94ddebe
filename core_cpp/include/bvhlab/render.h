// render.h — what a frame is made of (scene in GPU layout, camera, light, settings), what a render
// produces (colour, depth, traversal cost), renders in sample passes (RenderJob), and the CPU
// reference renderer. The Vulkan renderer (vulkan_renderer.h) reads the same RenderScene and
// FrameParams, and runs the same tracer code (shaders/tracer/*.glsl).
#pragma once
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "bvhlab/big_vector.h"
#include "bvhlab/bvh.h"
#include "bvhlab/cancel.h"
#include "bvhlab/depth_order.h"
#include "bvhlab/pair_nodes.h"
#include "bvhlab/render_defaults.h"
#include "bvhlab/render_settings.h"
#include "bvhlab/tlas.h"
#include "gpu_types.h"

namespace bvhlab {

/// Per-primitive materials, borrowed from the caller: M rows of kMaterialFloats floats (r, g, b,
/// reflective, transparent, ior, holdout: 0 or 1, hidden: the gpu::RAY_* bits of the rays that do not
/// see it; render_defaults.h) and one material index per triangle and per sphere.
struct MaterialView {
    const float* materials = nullptr;
    std::size_t material_count = 0;
    const std::int32_t* triangle_material = nullptr;  ///< null: every triangle uses material 0
    const std::int32_t* sphere_material = nullptr;    ///< null: every sphere uses material 0
};

/// The scene as both renderers read it: the tree, the geometry and materials in GPU layout,
/// and every node's box sorted by depth for the overlay (report §3.3.1).
/// A two-level scene (issue 34) has no `bvh`: its TLAS and every mesh's BLAS are copied into one
/// forest (forest_nodes, pairs, forest_prims: the TLAS first, each tree's indices moved to its place
/// there), its triangles and spheres are every mesh's, one after another, and `instances` places
/// the BLASes (in the TLAS's leaf order). Its overlay boxes are the TLAS's, or any list of world
/// boxes by depth given with `set_overlay_boxes` (the add-on's BLAS boxes moved into the world).
struct RenderScene {
    const Bvh* bvh = nullptr;         ///< borrowed: must outlive the RenderScene (flat scenes)
    BigVector<gpu::BvhPair> pairs;    ///< the tree's internal nodes for the stack walk (pair_nodes.h)
    BigVector<BvhNode> forest_nodes;  ///< two-level: every tree's nodes (flat: bvh->nodes is read)
    BigVector<gpu::GpuTriangle>
        forest_prims;  ///< two-level: every BLAS's leaf primitives, refs into `triangles`/`spheres`
    std::vector<gpu::GpuInstance> instances;  ///< two-level: in the TLAS's leaf order; empty: a flat scene
    /// Two-level: the slot in `instances` of each of the TLAS's instances (Tlas::instances order;
    /// gpu::NO_INSTANCE for one the TLAS's tree leaves out: an instance of an empty mesh, never
    /// hit), and each mesh's first triangle and sphere in `triangles` and `spheres`: a hit of
    /// tlas.h's queries (an instance index, a mesh's own primitive) in the tracer's numbers (the
    /// wide traversal).
    std::vector<std::uint32_t> instance_slots, first_triangle, first_sphere;
    BigVector<gpu::GpuTriangle> triangles;
    std::vector<gpu::GpuSphere> spheres;
    std::vector<gpu::GpuMaterial> materials;
    /// Some material is a holdout: the render counts each pixel's covered samples, its alpha, also
    /// on an opaque film (FrameParams::count_covered)
    bool holdout = false;
    /// Some material hides from some rays (its `hidden` bits): the walks look at each hit's material
    /// (FrameParams::hidden_materials)
    bool hidden = false;
    BigVector<gpu::GpuBox> boxes;   ///< in `order`: the boxes of depth d are order.range(d, d)
    DepthOrder order;               ///< of the tree's nodes (depth_order.h), or of the boxes given
    std::uint32_t tree_height = 0;  ///< of the tree (two-level: the TLAS's), whatever boxes the overlay draws
    Aabb bounds;
    std::uint32_t node_count =
        0;  ///< of the tree (kept here: make_frame_params never reads `bvh`); two-level: the TLAS's
    std::uint32_t ref_count = 0;      ///< primitive references in the tree's leaves
    std::uint32_t stack_entries = 1;  ///< traversal stack entries a walk may need (two-level: TLAS's and a BLAS's)
    std::uint64_t walk_steps = 2;     ///< the most steps of work one walk can take (pixel_sums.cpp step_bound)
    /// The tree's geometry_fingerprint when this was made: a refit changes it, and the copies here
    /// (pairs, boxes) would no longer be the tree's.
    std::uint64_t tree_fingerprint = 0;

    std::uint32_t height() const { return tree_height; }
    bool two_level() const { return !instances.empty(); }
    const BvhNode* node_data() const { return two_level() ? forest_nodes.data() : bvh->nodes.data(); }
    const gpu::GpuTriangle* prim_data() const { return two_level() ? forest_prims.data() : bvh->prims.data(); }
};

/// Throws std::invalid_argument for material indices out of range, bad material values, a tree
/// built for other geometry, or nodes that are not a depth-first binary tree (make_pair_nodes).
RenderScene make_render_scene(const Bvh& bvh, const GeometryView& geometry, const MaterialView& materials);

/// A mesh of a two-level scene as the renderers take it: its tree (borrowed), its geometry and a
/// material index per triangle and per sphere (null: material 0) into the scene's one table.
struct RenderMesh {
    const Bvh* bvh = nullptr;
    GeometryView geometry;
    const std::int32_t* triangle_material = nullptr;
    const std::int32_t* sphere_material = nullptr;
};

/// The render scene of a two-level tree (tlas.h): `meshes[k]` is BLAS k of `tlas`, `materials` the
/// table (its index arrays unused). A TLAS of one identity instance gives exactly the flat render
/// scene of its mesh (the flat tracer, bit for bit). The arrays are copied: `tlas` may go, the
/// meshes' trees too. Throws std::invalid_argument as the flat make_render_scene does, for a mesh
/// count that is not the TLAS's, or a TLAS leaf with more than one instance (default_tlas_config
/// makes one per leaf; the tracer enters one instance per leaf).
RenderScene make_render_scene(const Tlas& tlas, const std::vector<RenderMesh>& meshes, const MaterialView& materials);

/// Makes the overlay pass draw `count` boxes (lo, hi: 3 floats each; depth: the depth each is
/// coloured by and picked by, non-decreasing) instead of the tree's node boxes: a two-level scene's
/// BLAS boxes moved into the world (issue 34). The caller bounds their number. Throws
/// std::invalid_argument for depths out of order, a non-finite coordinate or lo > hi.
void set_overlay_boxes(RenderScene& scene, const float* lo, const float* hi, const std::uint8_t* depth,
                       std::size_t count);

/// Throws std::invalid_argument when `scene` no longer describes its tree (refitted since it was
/// made: make it again), or has no pairs for the tree's internal nodes (not made by
/// make_render_scene). Both renderers call it before they read the scene.
void check_render_scene(const RenderScene& scene);

/// The box tests per primary ray the heatmap shows red (and above): settings.heatmap_scale, else
/// 8 × the height of the tree whose boxes the overlay draws (a two-level scene's: the TLAS's), at
/// least 8. The heatmap's legend (bvhlab.legend) reads it from here: one definition.
float heatmap_scale(const RenderScene& scene, const RenderSettings& settings);

/// The per-frame parameters both renderers read (device addresses and the per-dispatch fields
/// left zero; the Vulkan side fills them).
gpu::FrameParams make_frame_params(const RenderScene& scene, const RenderSettings& settings);

/// Where a render writes: width×height pixels, row 0 at the top. Null outputs are skipped.
struct RenderImages {
    float* color = nullptr;  ///< RGBA; MODE_SHADE: the Whitted image (alpha 1); MODE_HEATMAP: heat colours
    float* depth = nullptr;  ///< view-axis depth of the nearest primary hit over the pixel's samples
                             ///< (Blender's Z pass); kNoDepth where no sample hit anything
    float* cost = nullptr;   ///< box tests per primary ray, averaged over the pixel's samples
    float* heat = nullptr;   ///< RGBA: `cost` as heat colours (what MODE_HEATMAP shows), in either mode
    /// gpu::COUNTER_COUNT floats per pixel (TraversalCounter order): each counter per primary ray,
    /// averaged over the pixel's samples; needs RenderSettings::traversal_counters
    /// (std::invalid_argument otherwise)
    float* counters = nullptr;
};

/// The depth of a pixel where nothing was hit: what Cycles writes into its Depth pass there.
inline constexpr float kNoDepth = 1e10f;

struct RenderTimings {
    double upload_ms = 0, overlay_ms = 0, trace_ms = 0, readback_ms = 0, total_ms = 0;
    std::string device;                    ///< which device rendered
    std::uint32_t dispatches = 0;          ///< trace dispatches (CPU: the most budgets of steps a pixel needed)
    std::uint32_t steps_per_dispatch = 0;  ///< the last budget of steps per pixel and dispatch
    /// Traversal::Wide on the CPU in a scene with a transparent material (or one hidden from shadow
    /// rays): shadow rays whose nearest crossing was opaque (transmission 0 from the wide walk) and
    /// those whose nearest was transparent or hidden from them (left to the stack walk); 0
    /// elsewhere. Summed over the job's runs.
    std::uint64_t shadow_rays_opaque = 0, shadow_rays_glass = 0;
    /// Traversal::Wide on the CPU without RenderSettings::keep_cost: camera rays answered from the
    /// runs traced ahead (cpu_tracer.h trace_camera_rays); 0 elsewhere. Summed over the job's runs.
    std::uint64_t camera_rays_ahead = 0;
};

/// A pixel did not finish within RenderSettings::max_steps_per_pixel; no image is returned.
struct RenderIncomplete : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// A render in sample passes (issue 12: a viewport shows a coarse image first and refines, an F12
/// render honours Esc). Each pixel keeps running sums over its samples; run() adds samples to
/// every pixel, resolve() turns the sums into images at any time. Whole samples only are summed,
/// so a run stopped half-way leaves every pixel averaged over the samples it completed.
class RenderJob {
public:
    virtual ~RenderJob() = default;

    /// Traces until every pixel has min(samples, samples_per_pixel()) samples. `cancel` is polled
    /// between dispatches (Vulkan) or budgets of steps (CPU); when it asks to stop, throws Cancelled.
    /// `progress` (if given) receives the fraction of this run done before each poll.
    virtual void run(std::uint32_t samples, Cancellation* cancel = nullptr, double* progress = nullptr) = 0;
    /// The images of the samples so far (each pixel averaged over its own count). Throws
    /// std::invalid_argument for a cost or heat image of a job without RenderSettings::keep_cost.
    void resolve(const RenderImages& out) {
        if ((out.cost || out.heat) && !settings_.keep_cost)
            throw std::invalid_argument(
                "this render kept no cost (box tests per primary ray): ask for it when it starts (keep_cost)");
        resolve_images(out);
    }

    const RenderSettings& settings() const { return settings_; }
    std::uint32_t samples_per_pixel() const { return settings_.samples_per_axis * settings_.samples_per_axis; }
    /// Every pixel has at least this many samples.
    std::uint32_t samples_done() const { return samples_done_; }
    const RenderTimings& timings() const { return timings_; }

protected:
    explicit RenderJob(const RenderSettings& settings) : settings_(settings) {}
    virtual void resolve_images(const RenderImages& out) = 0;  ///< resolve's work, its outputs checked
    RenderSettings settings_;
    std::uint32_t samples_done_ = 0;
    RenderTimings timings_;
};

/// What Traversal::Wide walks (start_cpu): a flat scene's 8-wide copy, make_wide(*scene.bvh)
/// (borrowed, as the scene is; made by the job where null), or the TLAS a two-level scene was made
/// from with its meshes' trees and their wide copies in the scene's mesh order (copied by the job;
/// what it points to is borrowed; where null, the stack walk walks the scene).
struct WideTrees {
    const WideBvh* flat = nullptr;
    const TwoLevel* two_level = nullptr;
};

/// The CPU reference renderer: the same tracer code as the compute shader, on `threads` threads
/// (0 = all). `scene` is borrowed and must outlive the job. Throws std::invalid_argument for bad
/// settings (validate), and for `wide.two_level` that is not the scene's TLAS and meshes.
std::unique_ptr<RenderJob> start_cpu(const RenderScene& scene, const RenderSettings& settings,
                                     std::uint32_t threads = 0, const WideTrees& wide = {});

/// start_cpu, every sample, resolve: the whole render at once.
RenderTimings render_cpu(const RenderScene& scene, const RenderSettings& settings, const RenderImages& out,
                         std::uint32_t threads = 0, Cancellation* cancel = nullptr);

}  // namespace bvhlab
