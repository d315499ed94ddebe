// cpu_tracer.h — the CPU reference tracer: the shared GLSL tracer code (shaders/tracer/*.glsl)
// compiled as member functions of this class (geometry.glsl's ray tests, which the CPU traversal
// shares, at namespace scope: shared_geometry.h), over the same arrays the GPU reads. The accessors
// below play the part of trace.comp's buffer references and storage image; one CpuTracer is one
// slot (a thread traces its pixels one after another through it).
#pragma once
#include <array>
#include <vector>

#include "bvhlab/isa.h"
#include "bvhlab/render.h"
#include "bvhlab/shared_geometry.h"
#include "bvhlab/wide_bvh.h"
#include "camera_packets.h"
#include "gpu_types.h"
#include "pixel_sums.h"

namespace bvhlab::gpu {

/// What TRAVERSAL_WIDE answers queries with (render.h start_cpu): a flat scene's 8-wide copy (of
/// the scene's tree, RenderScene::bvh), or a two-level scene's TLAS and meshes (tlas.h's queries, Traversal::Wide); and
/// whether every material is opaque and seen by shadow rays (a blocked shadow ray's transmission is
/// then 0: wide_walk).
struct WideScene {
    const WideBvh* wide = nullptr;
    const TwoLevel* two_level = nullptr;
    bool opaque = false;
};

/// `Count`: traverse.glsl's COUNT_TRAVERSAL. A render that keeps the traversal counters runs
/// CpuTracerOf<true>; one that does not, CpuTracerOf<false>, which counts box tests only (the
/// heatmap's cost) and so runs the walk as it was before the counters.
template <bool Count>
class CpuTracerOf {
public:
    static constexpr bool COUNT_TRAVERSAL = Count;

    /// `overlay` (one vec4 per pixel) and `sums` may be null for the overlay rasterizer's use.
    /// `wide`: TRAVERSAL_WIDE's trees (null: it walks as the stack walk).
    CpuTracerOf(const RenderScene& scene, const FrameParams& params, const vec4* overlay, PixelSums* sums,
                uint traversal, const WideScene* wide = nullptr)
        : frame(params),
          TRAVERSAL(traversal),
          tree_nodes_(scene.node_data()),
          pairs_(scene.pairs.data()),
          leaf_prims_(scene.prim_data()),
          triangles_(scene.triangles.data()),
          scene_(scene),
          overlay_(overlay),
          sums_(sums),
          wide_(wide) {}

    FrameParams frame;
    uint TRAVERSAL;

    // The arrays the walk reads at every step, through pointers held here: scene_.bvh->nodes[i]
    // is three dependent loads (the scene, its tree, the vector's data) that the compiler must
    // repeat after every store the walk makes (it cannot prove they do not alias).
    BvhNode load_node(uint i) const { return tree_nodes_[i]; }
    BvhPair load_pair(uint i) const { return pairs_[i]; }
    GpuTriangle load_leaf_prim(uint i) const { return leaf_prims_[i]; }
    GpuTriangle load_triangle(uint i) const { return triangles_[i]; }
    GpuSphere load_sphere(uint i) const { return scene_.spheres[i]; }
    GpuMaterial load_material(uint i) const { return scene_.materials[i]; }
    GpuInstance load_instance(uint i) const { return scene_.instances[i]; }
    uint node_count() const { return frame.node_count; }
    bool two_level() const { return frame.instance_count != 0u; }
    vec4 overlay_at(uvec2 p) const { return overlay_ ? overlay_[pixel_index(p)] : vec4(0.0f); }

    uint sync_steps(uint steps) const { return steps; }  // one lane: nothing to agree on

    // The slot: a suspended trace and its two stacks (sized for the largest settings).
    uvec4 state_load(uint k) const { return state_[k]; }
    void state_store(uint k, uvec4 w) { state_[k] = w; }
    uvec4 ray_word_load(uint k) const { return rays_[k]; }
    void ray_word_store(uint k, uvec4 w) { rays_[k] = w; }
    uvec2 node_stack_load(uint k) const { return nodes_[k]; }
    void node_stack_store(uint k, uvec2 e) { nodes_[k] = e; }

    // The pixel's sums (a pixel is traced by one thread at a time).
    std::size_t pixel_index(uvec2 p) const { return std::size_t(p.y) * frame.width + p.x; }
    uint samples_done(uvec2 p) const { return sums_->samples[pixel_index(p)]; }
    void accumulate_sample(uvec2 p, vec3 color, TraversalCounts counts, float depth, bool covered) {
        const std::size_t i = pixel_index(p);
        sums_->color[i] = sums_->color[i] + vec4(color, float(counts.box_tests));
        sums_->depth[i] = min(sums_->depth[i], depth);
        sums_->samples[i] = sums_->samples[i] + 1u;
        if (frame.count_covered) sums_->covered[i] += covered ? 1u : 0u;
        if (Count && frame.count_traversal) add_counts(sums_->counts[i], counts);
    }

#include "tracer/traverse.glsl"

    /// TRAVERSAL_WIDE (traverse.glsl walk): the query answered by the CPU queries' 8-wide walks in
    /// one step, the hit the stack walk finds (the same ray tests, geometry.glsl, and tie rule;
    /// flat: intersect_wide, bit for bit; two-level: intersect_two_level, whose instance and
    /// primitive are mapped to the scene's slot and reference). Its cost: flat, 8 box tests a wide
    /// node visited; two-level, the query's count (the TLAS's child boxes, a BLAS's wide nodes).
    /// A shadow ray where every material is opaque is an any-hit query: blocked, its transmission
    /// is 0 (occluded is exactly "some crossing before tmax", as the stack walk counts crossings).
    /// Where a material is transparent the stack walk's transmission is a product over the
    /// crossings taken in its order (three factors multiplied in another order can round otherwise),
    /// so the wide walk finds the ray's nearest crossing instead: none, transmission 1; an opaque
    /// surface, 0, which the stack walk's product is in any order (a factor of 0 among factors in
    /// [0, 1]); a transparent one, the ray is left to the stack walk (returns false). The shadow
    /// rays so answered are counted (shadow_opaque, shadow_glass: RenderTimings). A surface whose
    /// material hides from the ray's kind (traverse.glsl sees) is not in the wide trees' answers:
    /// where the nearest hit or crossing is one, the ray is left to the stack walk, which passes
    /// through it (counted as shadow_glass for a shadow ray). Returns false too where there is no
    /// wide tree.
    bool wide_walk(INOUT(Walk) w, TraceRay r, uint kind, INOUT(Hit) hit, INOUT(uint) work, INOUT(uint) steps) {
        if (wide_ == nullptr) return false;
        const bool shadow = kind == RAY_SHADOW;
        const Ray ray{{r.origin.x, r.origin.y, r.origin.z}, {r.dir.x, r.dir.y, r.dir.z}, r.tmin, hit.t};
        if (shadow && wide_->opaque) {
            const bool blocked = wide_->two_level ? occluded_two_level(*wide_->two_level, ray, Traversal::Wide)
                                                  : occluded_wide(*wide_->wide, ray);
            if (blocked) hit.transmission = 0.0f;
        } else if (shadow) {
            Hit nearest = hit;
            nearest_hit(ray, nearest);
            if (nearest.ref != NO_HIT) {
                if (load_material(material_of(nearest.ref)).transparent_ior.x != 0.0f || !sees(nearest.ref, kind)) {
                    shadow_glass += 1u;
                    return false;
                }
                shadow_opaque += 1u;
                hit.transmission = 0.0f;
            }
        } else {
            Hit nearest = hit;
            nearest_hit(ray, nearest, kind == RAY_CAMERA);
            if (nearest.ref != NO_HIT && !sees(nearest.ref, kind)) return false;
            hit = nearest;
        }
        w.state = WALK_FINISHED;
        steps += 1u;
        work += 1u;
        return true;
    }
    /// The closest hit of `ray` through the wide trees into `hit` (the scene's reference and
    /// instance slot; untouched on a miss) and its cost: flat, 8 box tests a wide node visited;
    /// two-level, the query's count. A flat scene's `camera` ray that the pixel's run traced
    /// ahead (trace_camera_rays) takes that hit, the same, and counts nothing.
    void nearest_hit(const Ray& ray, INOUT(Hit) hit, bool camera = false) {
        std::uint32_t visited = 0;
        if (wide_->two_level) {
            const InstanceHit h = intersect_two_level(*wide_->two_level, ray, Traversal::Wide, &visited);
            if (h.hit.ref != kNoHit) {
                const std::uint32_t mesh = wide_->two_level->tlas->instances[h.instance].blas;
                const bool sphere = (h.hit.ref & REF_SPHERE_BIT) != 0u;
                hit.t = h.hit.t, hit.u = h.hit.u, hit.v = h.hit.v;
                hit.ref = sphere ? REF_SPHERE_BIT | ((h.hit.ref & REF_INDEX_MASK) + scene_.first_sphere[mesh])
                                 : h.hit.ref + scene_.first_triangle[mesh];
                hit.instance = scene_.instance_slots[h.instance];
            }
            hit.counts.box_tests += visited;
        } else {
            bvhlab::Hit h;
            if (!(camera && camera_.find(camera_slot_, ray, h))) {
                h = intersect_wide(*wide_->wide, *scene_.bvh, ray, &visited);
                hit.counts.box_tests += 8u * visited;
            } else {
                camera_ahead += 1u;
            }
            if (h.ref != kNoHit) hit.t = h.t, hit.ref = h.ref, hit.u = h.u, hit.v = h.v;
        }
    }

    /// Shadow rays of a scene with a transparent material the wide walk answered: nearest crossing
    /// opaque (transmission 0), and nearest crossing transparent (left to the stack walk).
    std::uint64_t shadow_opaque = 0, shadow_glass = 0;
    /// Camera rays nearest_hit answered from a run traced ahead (RenderTimings::camera_rays_ahead).
    std::uint64_t camera_ahead = 0;

#include "tracer/shade_colors.glsl"
#include "tracer/shade.glsl"
#include "tracer/state.glsl"
#include "tracer/overlay.glsl"

    /// Whether the camera rays of a flat scene's wide walk are worth tracing ahead
    /// (trace_camera_rays): where the batch walk has packets (the AVX2 path, wide_packet.inl;
    /// elsewhere it would walk them alone all the same).
    bool traces_camera_rays_ahead() const {
        return wide_ != nullptr && wide_->wide != nullptr && active_isa() >= Isa::Avx2;
    }

    /// Traces ahead the camera queries of pixels [x0, x1) of row y, each pixel's samples from
    /// samples_done to frame.sample_target (camera_packets.h), which nearest_hit then answers
    /// from, and camera_task takes the rays from, until the next run: each query as the trace
    /// makes it (camera_ray, has_ray, query_span: start_sample and start_closest). Only for a
    /// render without the cost (RenderSettings::keep_cost), which packets do not count, and a flat
    /// scene (traces_camera_rays_ahead).
    void trace_camera_rays(uint y, uint x0, uint x1) {
        camera_.begin(y, x0, x1 - x0);
        camera_tasks_.clear();
        camera_slot_ = kNoHit;
        for (uint x = x0; x < x1; ++x) {
            const uvec2 p(x, y);
            const uint first = samples_done(p), target = frame.sample_target;
            const vec4 overlay = overlay_at(p);
            camera_.pixel(x - x0, first, target > first ? target - first : 0u);
            for (uint k = first; k < target; ++k) {
                const RayTask task = camera_ray(p, k);
                const bool traced = has_ray(task);
                Ray ray{};
                if (traced) {
                    const vec2 span = query_span(task, overlay);
                    ray = Ray{{task.origin.x, task.origin.y, task.origin.z},
                              {task.dir.x, task.dir.y, task.dir.z},
                              span.x,
                              span.y};
                    camera_tasks_.push_back(task);
                }
                camera_.add(ray, traced);
            }
        }
        camera_.trace(*wide_->wide, *scene_.bvh);
    }
    /// start_sample's camera ray of pixel p's sample: the one the run traced ahead, else
    /// camera_ray's (the same function of the same pixel and sample: the same bits). The sample's
    /// camera query (nearest_hit) is then answered from that ray's slot.
    RayTask camera_task(uvec2 p, uint sample_index) {
        camera_slot_ = camera_.slot(p.x, p.y, sample_index);
        return camera_slot_ != kNoHit ? camera_tasks_[camera_slot_] : camera_ray(p, sample_index);
    }

private:
    const BvhNode* tree_nodes_;
    const BvhPair* pairs_;
    const GpuTriangle* leaf_prims_;
    const GpuTriangle* triangles_;
    const RenderScene& scene_;
    const vec4* overlay_;
    PixelSums* sums_;
    const WideScene* wide_;
    CameraPackets camera_;                ///< the run's camera rays traced ahead (trace_camera_rays)
    std::vector<RayTask> camera_tasks_;   ///< the run's camera rays as tasks, by camera_.slot
    std::uint32_t camera_slot_ = kNoHit;  ///< the slot of the sample camera_task last gave
    std::array<uvec4, STATE_WORDS> state_{};
    std::array<uvec4, 3 * RAY_STACK_SIZE> rays_{};
    std::array<uvec2, 2 * MAX_TREE_HEIGHT> nodes_{};  ///< two-level: a TLAS's entries and a BLAS's
};

/// The tracer with every counter (the inspector's pixel rays and the overlay rasterizer, which
/// count nothing, take it too).
using CpuTracer = CpuTracerOf<true>;

}  // namespace bvhlab::gpu
