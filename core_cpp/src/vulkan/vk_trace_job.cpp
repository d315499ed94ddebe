// A render on the GPU in bounded dispatches (issue 8): the image is cut into tiles whose traces
// fit the slot memory; each tile is dispatched round after round, every invocation running at most
// a budget of tracer steps and saving where it stands, until no slot has work left. The budget
// stays under lavapipe's loop limit (gpu::MAX_STEPS_PER_DISPATCH) and adapts so that a round takes
// about kRoundTargetMs, which keeps GPU watchdogs quiet and Esc / Ctrl-C prompt (polled between
// rounds). The sums per pixel stay on the device until resolve().
#include <algorithm>
#include <chrono>
#include <cstddef>
#include <stdexcept>
#include <vector>

#include "../render/pixel_sums.h"
#include "vk_passes.h"
#include "vk_renderer_core.h"

namespace bvhlab::vk {
namespace {

/// Memory for the slots of one tile: suspended states and their stacks.
constexpr std::size_t kSlotBytes = std::size_t(64) << 20;
constexpr double kRoundTargetMs = 100.0;
/// The first round's steps per invocation: about 2^28 for the whole tile (most pixels of ordinary
/// scenes finish in one round), between kFirstRoundMinSteps and kFirstRoundMaxSteps; later rounds
/// adapt to their time. The cap bounds a small image's first round where every pixel needs far
/// more (2^28 / 4,096 pixels was the whole 60,000 a pixel: 64 × 64 over 100,000 coincident
/// triangles ran 17 s on lavapipe before its first look at Ctrl-C, probe; 2,048 a pixel, ~0.6 s).
constexpr std::uint64_t kFirstRoundSteps = std::uint64_t(1) << 28;
constexpr std::uint32_t kFirstRoundMinSteps = 1024;
constexpr std::uint32_t kFirstRoundMaxSteps = 2048;
constexpr std::uint32_t kMinSteps = 64;

std::uint32_t round_up(std::uint32_t x, std::uint32_t m) { return (x + m - 1) / m * m; }

/// A grid of tiles over the image: `width` × `height` pixels each (the last column and row cut to
/// the image), multiples of the workgroup size.
struct Tiling {
    std::uint32_t width, height, columns, rows;

    Tiling(std::uint32_t image_width, std::uint32_t image_height, std::size_t bytes_per_slot) {
        const std::size_t slots = std::max<std::size_t>(kSlotBytes / bytes_per_slot, 64 * 64);
        width = std::min(round_up(image_width, gpu::TRACE_GROUP_X), 2048u);
        const std::size_t rows_fit = slots / width / gpu::TRACE_GROUP_Y * gpu::TRACE_GROUP_Y;
        height = std::uint32_t(
            std::clamp<std::size_t>(rows_fit, gpu::TRACE_GROUP_Y, round_up(image_height, gpu::TRACE_GROUP_Y)));
        columns = (image_width + width - 1) / width;
        rows = (image_height + height - 1) / height;
    }
    std::uint32_t count() const { return columns * rows; }
};

class VulkanRenderJob final : public RenderJob {
public:
    VulkanRenderJob(std::shared_ptr<RendererCore> core, std::shared_ptr<const SceneBuffers> scene,
                    const RenderSettings& settings)
        : RenderJob(settings),
          core_(std::move(core)),
          scene_(std::move(scene)),
          frame_(scene_->frame_params(settings)),
          tiles_(settings.width, settings.height, slot_bytes(frame_)) {
        const auto lock = lock_in_slices(core_->mutex);
        serial_ = ++core_->jobs;
        frame_.overlay_line_width = core_->line_width(settings);  // what this device draws
        sums_.emplace(core_->device, std::size_t(settings.width) * settings.height, settings.traversal_counters,
                      frame_.count_covered != 0);
        sums_->address(frame_);
        core_->runner.run([&](VkCommandBuffer cmd) {
            record_fill(core_->fn, cmd, sums_->color, 0u);
            record_fill(core_->fn, cmd, sums_->depth, 0x7f800000u);  // +inf: nothing hit yet
            record_fill(core_->fn, cmd, sums_->samples, 0u);
            if (sums_->counts.size()) record_fill(core_->fn, cmd, sums_->counts, 0u);
            if (sums_->covered.size()) record_fill(core_->fn, cmd, sums_->covered, 0u);
        });
        timings_.device = core_->device.physical().name();
        budget_ = settings.steps_per_dispatch.value_or(
            std::uint32_t(std::clamp<std::uint64_t>(kFirstRoundSteps / (std::uint64_t(tiles_.width) * tiles_.height),
                                                    kFirstRoundMinSteps, kFirstRoundMaxSteps)));
    }

    void run(std::uint32_t samples, Cancellation* cancel, double* progress) override {
        const std::uint32_t target = std::min(samples, samples_per_pixel());
        if (target <= samples_done_) return;
        const auto lock = lock_in_slices(core_->mutex);
        gpu::FrameParams frame = frame_;
        frame.sample_target = target;
        frame.max_work_per_pixel = work_cap(scene_->summary(), settings_, target - samples_done_);
        prepare(frame, cancel);
        for (std::uint32_t t = 0; t < tiles_.count(); ++t) run_tile(frame, t, cancel, progress);
        timings_.total_ms = timings_.overlay_ms + timings_.trace_ms;
        samples_done_ = target;
    }

    void resolve_images(const RenderImages& out) override {
        const auto start = std::chrono::steady_clock::now();
        {
            const auto lock = lock_in_slices(core_->mutex);  // held while the core's readback buffer is read
            // The sums the images ask for alone: colour and samples always, depth and the counters
            // where `out` wants them (a viewport's colour: 20 bytes a pixel of 24, or of 44 where
            // the render keeps counters)
            const SumBuffers& b = *sums_;
            const std::size_t n = b.pixels;
            const bool counts = out.counters && b.counts.size(), covered = out.color && b.covered.size();
            std::vector<Read> reads{{&b.color, n * sizeof(gpu::vec4)}, {&b.samples, n * sizeof(std::uint32_t)}};
            if (out.depth) reads.push_back({&b.depth, n * sizeof(float)});
            if (counts) reads.push_back({&b.counts, n * sizeof(gpu::TraversalCounts)});
            if (covered) reads.push_back({&b.covered, n * sizeof(std::uint32_t)});
            const std::vector<const std::byte*> at = read(reads);
            PixelSums::View sums{reinterpret_cast<const gpu::vec4*>(at[0]), nullptr,
                                 reinterpret_cast<const std::uint32_t*>(at[1]), nullptr, n};
            std::size_t next = 2;
            if (out.depth) sums.depth = reinterpret_cast<const float*>(at[next++]);
            if (counts) sums.counts = reinterpret_cast<const gpu::TraversalCounts*>(at[next++]);
            if (covered) sums.covered = reinterpret_cast<const std::uint32_t*>(at[next++]);
            bvhlab::resolve(sums, frame_, out);
        }
        timings_.readback_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    }

private:
    static std::size_t slot_bytes(const gpu::FrameParams& f) {
        return gpu::STATE_WORDS * sizeof(gpu::uvec4) + 3 * sizeof(gpu::uvec4) * f.ray_stack_entries +
               sizeof(gpu::uvec2) * f.node_stack_entries;
    }

    /// Slots and overlay targets for this job (another job may have used them since), then the
    /// overlay pass, or a clear: the trace pass reads the image either way. The overlay is drawn
    /// in parts of kOverlayBoxesPerPart boxes, one submission each, `cancel` polled between them;
    /// and once a job: a later run() finds it in the targets unless another job drew there since
    /// (each run of a progressive render drew it again: 3.8 s a run over 2M boxes, probe).
    void prepare(gpu::FrameParams& frame, Cancellation* cancel) {
        RendererCore& c = *core_;
        if (c.slots.reserve(tiles_.width * tiles_.height, frame.ray_stack_entries, frame.node_stack_entries))
            c.runner.run([&](VkCommandBuffer cmd) { record_fill(c.fn, cmd, c.slots.state(), 0u); });
        c.slots.address(frame);
        c.ensure_targets(settings_.width, settings_.height);
        c.bindings.write_params(frame);
        if (c.overlay_job == serial_) return;
        c.overlay_job = 0;  // the targets hold no job's overlay until its last part is drawn
        const PassContext pass = c.pass();
        if (!frame.overlay_enabled) {
            timings_.overlay_ms += c.runner.run([&](VkCommandBuffer cmd) { record_clear(pass, cmd); });
        } else {
            const std::uint32_t first = frame.overlay_first_box, last = frame.overlay_last_box;
            for (std::uint32_t at = first;;) {
                const std::uint32_t count = std::min(last - at, kOverlayBoxesPerPart);
                const OverlayPart part{at, count, at == first, at + count == last};
                timings_.overlay_ms += c.runner.run(
                    [&](VkCommandBuffer cmd) { record_overlay(pass, cmd, frame.overlay_line_width, part); });
                at += count;
                if (part.closes) break;
                if (cancel && cancel->poll()) throw Cancelled();
            }
        }
        c.overlay_job = serial_;
    }

    /// Rounds over tile `index` until each of its pixels has its samples, or `cancel` says stop
    /// (Cancelled), or a pixel's trace failed: more work than frame.max_work_per_pixel (RenderIncomplete).
    void run_tile(gpu::FrameParams frame, std::uint32_t index, Cancellation* cancel, double* progress) {
        RendererCore& c = *core_;
        frame.tile_x = index % tiles_.columns * tiles_.width;
        frame.tile_y = index / tiles_.columns * tiles_.height;
        frame.tile_width = std::min(tiles_.width, settings_.width - frame.tile_x);
        frame.tile_height = std::min(tiles_.height, settings_.height - frame.tile_y);
        frame.stamp = c.next_stamp();
        const double tile_pixels = double(frame.tile_width) * frame.tile_height;
        std::uint32_t unfinished = std::uint32_t(tile_pixels);
        for (;;) {
            if (progress) *progress = (index + 1.0 - unfinished / tile_pixels) / tiles_.count();
            if (cancel && cancel->poll()) throw Cancelled();
            frame.steps_per_dispatch = budget_;
            c.bindings.write_params(frame);
            c.slots.reset_counters();
            const PassContext pass = c.pass();
            const double ms = c.runner.run([&](VkCommandBuffer cmd) {
                record_trace_round(pass, cmd, gpu_traversal(settings_.traversal), frame.tile_width, frame.tile_height);
            });
            timings_.trace_ms += ms;
            timings_.dispatches += 1;
            timings_.steps_per_dispatch = frame.steps_per_dispatch;
            if (const std::uint32_t failed = c.slots.failed())
                throw RenderIncomplete(incomplete_message(failed, frame.max_work_per_pixel));
            unfinished = c.slots.unfinished();
            if (unfinished == 0) return;
            adapt_budget(ms);
        }
    }

    /// Aims at rounds of about kRoundTargetMs (unless the settings fix the budget).
    void adapt_budget(double ms) {
        if (settings_.steps_per_dispatch) return;
        if (ms > 2 * kRoundTargetMs) budget_ = std::max(kMinSteps, std::uint32_t(budget_ * (kRoundTargetMs / ms)));
        else if (ms < kRoundTargetMs / 2) budget_ = std::min(gpu::MAX_STEPS_PER_DISPATCH, budget_ * 2);
    }

    /// A device buffer's first `bytes`.
    struct Read {
        const Buffer* from;
        std::size_t bytes;
    };

    /// Device → host: where the host reads each read's bytes in place, resolve reading the sums
    /// there (copied into a PixelSums first, with heat colours made for every pixel, lavapipe's
    /// readback at 800×600 was 2.8-4.4 ms; in place, 1.3-1.8 on one thread, 0.9-2.0 on two). The
    /// buffers' own mapped memory where it is host-visible (lavapipe, integrated GPUs), else the
    /// core's readback buffer, which one submission copies all of them into (made or grown here:
    /// the caller holds the core's lock, and keeps it while it reads). A buffer made and a
    /// submission waited for per read, as before that, took 11.5 ms of a 13.9 ms frame at 800×600
    /// on an NVIDIA H200 (its first GPU run, the trace 1.3 ms). The renderer's force_staging takes
    /// the copy on any device (the tests' staging case).
    std::vector<const std::byte*> read(const std::vector<Read>& reads) {
        RendererCore& c = *core_;
        std::vector<const std::byte*> at;
        bool visible = !c.force_staging;
        for (const Read& r : reads) visible = visible && r.from->host_visible();
        if (visible) {
            for (const Read& r : reads) at.push_back(r.from->host_bytes(r.bytes));
            return at;
        }
        std::vector<HostCopy> copies;
        VkDeviceSize total = 0;
        for (const Read& r : reads) {
            if (r.bytes > r.from->size()) throw std::logic_error("a read past the end of a device buffer");
            copies.push_back({r.from, r.bytes, total});
            total += (r.bytes + 15) & ~VkDeviceSize(15);
        }
        if (!c.readback || c.readback->size() < total)
            c.readback.emplace(c.device, total, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::Readback);
        c.runner.run(
            [&](VkCommandBuffer cmd) { record_copies_to_host(c.fn, cmd, copies.data(), copies.size(), *c.readback); });
        for (std::size_t k = 0; k < reads.size(); ++k)
            at.push_back(c.readback->host_bytes(reads[k].bytes, copies[k].offset));
        return at;
    }

    // Declared in creation order: the device buffers go before the device.
    std::shared_ptr<RendererCore> core_;
    std::shared_ptr<const SceneBuffers> scene_;
    gpu::FrameParams frame_;
    Tiling tiles_;
    std::optional<SumBuffers> sums_;
    std::uint32_t budget_ = gpu::MAX_STEPS_PER_DISPATCH;
    std::uint64_t serial_ = 0;  ///< this job's number among the core's (RendererCore::jobs)
};

}  // namespace

std::unique_ptr<RenderJob> start_vulkan_job(std::shared_ptr<RendererCore> core,
                                            std::shared_ptr<const SceneBuffers> scene, const RenderSettings& settings) {
    return std::make_unique<VulkanRenderJob>(std::move(core), std::move(scene), settings);
}

}  // namespace bvhlab::vk
