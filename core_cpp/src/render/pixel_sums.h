// pixel_sums.h — a render's running sums per pixel (RenderJob, render.h), as the trace writes them
// (accumulate_sample in shaders/trace.comp and cpu_tracer.h), and the one step that turns them
// into images for both renderers.
#pragma once
#include <cstdint>
#include <vector>

#include "bvhlab/big_vector.h"
#include "bvhlab/render.h"

namespace bvhlab {

struct PixelSums {
    BigVector<gpu::vec4> color;        ///< rgb: sum of sample colours; a: sum of box tests
    BigVector<float> depth;            ///< nearest view-axis depth of a primary hit (inf: none)
    BigVector<std::uint32_t> samples;  ///< samples summed
    /// Traversal counters summed over the samples (issue 35); empty unless the render keeps them
    /// (RenderSettings::traversal_counters: 20 bytes a pixel).
    BigVector<gpu::TraversalCounts> counts;
    /// Samples whose camera ray showed something but a holdout (with RenderSettings::
    /// film_transparent: a surface or the overlay's line), the alpha; empty unless the frame counts
    /// them (FrameParams::count_covered: a transparent film, or a scene with a holdout).
    BigVector<std::uint32_t> covered;

    /// Zero sums for `pixels` pixels, with counters where `counters` and covered samples where
    /// `covered_samples` (std::bad_alloc if they do not fit).
    explicit PixelSums(std::size_t pixels = 0, bool counters = false, bool covered_samples = false);

    struct View;
    View view() const;
};

/// Sums of `pixels` pixels, read-only, wherever they lie: a PixelSums, or the Vulkan renderer's
/// mapped memory, which resolve reads in place rather than copied into a PixelSums first
/// (vk_trace_job.cpp read(): lavapipe's readback and resolve at 800×600 2.8-4.4 → 1.3-1.8 ms on
/// one thread, with heat colours made only where shown).
struct PixelSums::View {
    const gpu::vec4* color = nullptr;
    const float* depth = nullptr;  ///< may be null where the images want no depth
    const std::uint32_t* samples = nullptr;
    const gpu::TraversalCounts* counts = nullptr;  ///< null where the render keeps no counters
    std::size_t pixels = 0;
    const std::uint32_t* covered = nullptr;  ///< null where the frame counts no alpha (count_covered)
};

/// `sum` += `c`, counter by counter.
inline void add_counts(gpu::TraversalCounts& sum, const gpu::TraversalCounts& c) {
    sum.box_tests += c.box_tests, sum.box_hits += c.box_hits, sum.prim_tests += c.prim_tests;
    sum.prim_hits += c.prim_hits, sum.instance_hits += c.instance_hits;
}

/// Colour (or heat colours), depth and cost of each pixel from its sums: the average of its
/// samples; a pixel without samples is transparent black with depth kNoDepth and cost 0. With
/// frame.count_covered, a shaded pixel's alpha is its covered samples' share (its colour is
/// premultiplied already: the samples that showed nothing, or a holdout, added none). On up to
/// `threads` threads of the shared pool (0: every hardware thread), in blocks of pixels.
void resolve(const PixelSums::View& sums, const gpu::FrameParams& frame, const RenderImages& out, unsigned threads = 0);

/// The most tracer steps a correct trace of `samples` samples of one pixel can take: per sample,
/// at most 2^(max_ray_depth + 1) - 1 rays, each a closest-hit and a shadow walk of at most
/// 2·nodes + references + 2 steps (each node visited once, each primitive tested once, a pop per
/// push), plus the step that starts the sample. Saturates at UINT64_MAX.
std::uint64_t step_bound(const RenderScene& scene, const RenderSettings& settings, std::uint32_t samples);

/// FrameParams::max_work_per_pixel of a run of `samples` samples: settings.max_steps_per_pixel,
/// else step_bound; gpu::NO_WORK_CAP where that does not fit 32 bits.
std::uint32_t work_cap(const RenderScene& scene, const RenderSettings& settings, std::uint32_t samples);

/// The message of RenderIncomplete.
std::string incomplete_message(std::uint64_t pixels, std::uint64_t cap);

}  // namespace bvhlab
