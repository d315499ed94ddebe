// Running sums per pixel and the resolve step both renderers share.
#include "pixel_sums.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "bvhlab/palette.h"
#include "bvhlab/thread_pool.h"

namespace bvhlab {
namespace {

std::uint64_t saturating_mul(std::uint64_t a, std::uint64_t b) {
    if (a != 0 && b > std::numeric_limits<std::uint64_t>::max() / a) return std::numeric_limits<std::uint64_t>::max();
    return a * b;
}

}  // namespace

PixelSums::PixelSums(std::size_t pixels, bool counters, bool covered_samples) {
    color.assign(pixels, gpu::vec4(0.0f));
    depth.assign(pixels, std::numeric_limits<float>::infinity());
    samples.assign(pixels, 0u);
    if (counters) counts.assign(pixels, gpu::TraversalCounts{});
    if (covered_samples) covered.assign(pixels, 0u);
}

PixelSums::View PixelSums::view() const {
    return {color.data(),   depth.data(),
            samples.data(), counts.empty() ? nullptr : counts.data(),
            color.size(),   covered.empty() ? nullptr : covered.data()};
}

namespace {

/// Pixels a task of resolve's: small enough that two threads share an 800×600 frame evenly, large
/// enough that handing it out costs nothing beside it.
constexpr std::size_t kResolveBlock = std::size_t(1) << 14;

/// Each counter of pixel `i` per primary ray (the average over its samples; 0 without samples).
void resolve_counts(const PixelSums::View& sums, std::size_t i, float* out) {
    const std::uint32_t n = sums.samples[i];
    const gpu::TraversalCounts& c = sums.counts[i];
    const std::uint32_t values[gpu::COUNTER_COUNT] = {c.box_tests, c.box_hits, c.prim_tests, c.prim_hits,
                                                      c.instance_hits};
    for (std::uint32_t k = 0; k < gpu::COUNTER_COUNT; ++k) out[k] = n > 0 ? float(double(values[k]) / n) : 0.0f;
}

/// Pixels [begin, end) of resolve. Heat colours only where an image shows them.
void resolve_block(const PixelSums::View& sums, const gpu::FrameParams& frame, const RenderImages& out,
                   std::size_t begin, std::size_t end) {
    gpu::Palette palette;
    const bool heatmap = frame.mode == gpu::MODE_HEATMAP, need_heat = out.heat || (out.color && heatmap);
    // the covered samples are read only for a shaded colour image (resolve checks they are there)
    const bool transparent = frame.count_covered && !heatmap && out.color;
    auto store = [](float* image, std::size_t i, const gpu::vec4& v) {
        float* c = image + 4 * i;
        c[0] = v.x, c[1] = v.y, c[2] = v.z, c[3] = v.w;
    };
    for (std::size_t i = begin; i < end; ++i) {
        const std::uint32_t n = sums.samples[i];
        gpu::vec4 rgba(0.0f), heat(0.0f);
        float cost = 0.0f;
        if (n > 0) {
            const float count = float(n);
            const gpu::vec4 s = sums.color[i];
            cost = s.w / count;
            if (need_heat) heat = gpu::vec4(palette.heat_color(cost / frame.heatmap_scale), 1.0f);
            const float alpha = transparent ? float(sums.covered[i]) / count : 1.0f;
            rgba = heatmap ? heat : gpu::vec4(gpu::vec3(s.x, s.y, s.z) / count, alpha);
        }
        if (out.color) store(out.color, i, rgba);
        if (out.heat) store(out.heat, i, heat);
        if (out.depth) out.depth[i] = std::isinf(sums.depth[i]) ? kNoDepth : sums.depth[i];
        if (out.cost) out.cost[i] = cost;
        if (out.counters) resolve_counts(sums, i, out.counters + gpu::COUNTER_COUNT * i);
    }
}

}  // namespace

void resolve(const PixelSums::View& sums, const gpu::FrameParams& frame, const RenderImages& out, unsigned threads) {
    if (out.counters && !sums.counts)
        throw std::invalid_argument(
            "this render kept no traversal counters: ask for them when it starts (traversal_counters)");
    const std::size_t pixels = std::size_t(frame.width) * frame.height;
    if (pixels > sums.pixels) throw std::logic_error("resolve: fewer sums than the frame's pixels");
    if (out.depth && !sums.depth) throw std::logic_error("resolve: a depth image without the depth sums");
    if (out.color && frame.count_covered && !sums.covered)
        throw std::logic_error("resolve: an image with alpha without the covered samples");
    const std::size_t blocks = (pixels + kResolveBlock - 1) / kResolveBlock;
    ThreadPool::shared().run(blocks, threads, [&](std::size_t b, unsigned) {
        resolve_block(sums, frame, out, b * kResolveBlock, std::min(pixels, (b + 1) * kResolveBlock));
    });
}

std::uint64_t step_bound(const RenderScene& scene, const RenderSettings& settings, std::uint32_t samples) {
    const std::uint64_t walk = scene.walk_steps;
    const std::uint64_t rays = (1ull << (settings.max_ray_depth + 1)) - 1;
    const std::uint64_t per_sample = saturating_mul(saturating_mul(rays, 2), walk) + 1;
    return saturating_mul(per_sample, samples) + 1;
}

std::uint32_t work_cap(const RenderScene& scene, const RenderSettings& settings, std::uint32_t samples) {
    const std::uint64_t cap =
        settings.max_steps_per_pixel ? *settings.max_steps_per_pixel : step_bound(scene, settings, samples);
    return cap >= gpu::NO_WORK_CAP ? gpu::NO_WORK_CAP : std::uint32_t(cap);
}

std::string incomplete_message(std::uint64_t pixels, std::uint64_t cap) {
    // "at least": the render stops once a pixel fails, so the others were never all traced
    return "at least " + std::to_string(pixels) + " pixel(s) did not finish within " + std::to_string(cap) +
           " tracer steps (max_steps_per_pixel; the render stops at the first); no image is returned";
}

}  // namespace bvhlab
