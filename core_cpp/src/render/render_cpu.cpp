// The CPU reference renderer: the overlay pass, then every pixel through the shared tracer code in
// budgets of steps with the state saved and loaded between them exactly as the GPU does between
// dispatches, rows handed out to threads one at a time.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "cpu_tracer.h"
#include "overlay_cpu.h"
#include "pixel_sums.h"

namespace bvhlab {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

enum class PixelResult { Done, Failed, Stopped };

/// What the threads of one run share.
struct RunShared {
    std::atomic<std::uint32_t> next_row{0};
    std::atomic<std::uint64_t> pixels_done{0}, pixels_failed{0};
    std::atomic<std::uint32_t> most_budgets{0};  ///< budgets of steps the slowest pixel needed
    std::atomic<std::uint32_t> workers_left{0};
    std::mutex done_mutex;  ///< with done: the last worker wakes the polling caller
    std::condition_variable done;
    std::atomic<std::uint64_t> shadow_opaque{0}, shadow_glass{0};  ///< RenderTimings::shadow_rays_*
    std::atomic<std::uint64_t> camera_ahead{0};                    ///< RenderTimings::camera_rays_ahead
    std::atomic<bool> abort{false};                                ///< a pixel failed or threw: the run ends
    std::exception_ptr error;
    std::mutex error_mutex;
};

class CpuRenderJob final : public RenderJob {
public:
    CpuRenderJob(const RenderScene& scene, const RenderSettings& settings, std::uint32_t threads, const WideTrees& wide)
        : RenderJob(settings),
          scene_(scene),
          frame_(make_frame_params(scene, settings)),
          threads_(threads ? threads : std::max(1u, std::thread::hardware_concurrency())) {
        const auto start = Clock::now();
        if (settings.traversal == Traversal::Wide) prepare_wide(wide);
        overlay_ = rasterize_overlay(scene, frame_);
        sums_ = PixelSums(std::size_t(settings.width) * settings.height, settings.traversal_counters,
                          frame_.count_covered != 0);
        timings_.overlay_ms = ms_since(start);
        timings_.device = "CPU reference (" + std::to_string(threads_) + (threads_ == 1 ? " thread" : " threads") +
                          walk_note(settings) + ")";
        timings_.steps_per_dispatch = settings.steps_per_dispatch.value_or(gpu::MAX_STEPS_PER_DISPATCH);
    }

    void run(std::uint32_t samples, Cancellation* cancel, double* progress) override {
        const std::uint32_t target = std::min(samples, samples_per_pixel());
        if (target <= samples_done_) return;
        const auto start = Clock::now();
        gpu::FrameParams frame = frame_;
        frame.sample_target = target;
        frame.max_work_per_pixel = work_cap(scene_, settings_, target - samples_done_);
        RunShared shared;
        run_threads(frame, shared, cancel, progress);
        timings_.trace_ms += ms_since(start);
        timings_.total_ms = timings_.overlay_ms + timings_.trace_ms;
        timings_.dispatches += shared.most_budgets.load();
        timings_.shadow_rays_opaque += shared.shadow_opaque.load();
        timings_.shadow_rays_glass += shared.shadow_glass.load();
        timings_.camera_rays_ahead += shared.camera_ahead.load();
        if (shared.error) std::rethrow_exception(shared.error);
        if (cancel && cancel->stop_requested()) throw Cancelled();
        if (shared.pixels_failed)
            throw RenderIncomplete(incomplete_message(shared.pixels_failed, frame.max_work_per_pixel));
        samples_done_ = target;
    }

    void resolve_images(const RenderImages& out) override {
        const auto start = Clock::now();
        bvhlab::resolve(sums_.view(), frame_, out, threads_);
        timings_.readback_ms = ms_since(start);
    }

private:
    /// Traversal::Wide: a flat scene's wide copy (borrowed, or made here), or a two-level scene's
    /// TLAS and meshes (copied; checked against the scene; without them the stack walk walks it).
    void prepare_wide(const WideTrees& wide) {
        bool opaque = true;
        for (const gpu::GpuMaterial& m : scene_.materials)
            opaque =
                opaque && m.transparent_ior.x == 0.0f && (std::uint32_t(m.transparent_ior.w) & gpu::RAY_SHADOW) == 0u;
        if (scene_.two_level()) {
            if (wide.two_level == nullptr) return;
            check_two_level(*wide.two_level, Traversal::Wide);
            if (!made_from(*wide.two_level))
                throw std::invalid_argument(
                    "the wide traversal's TLAS and meshes are not the ones the scene was made from");
            two_level_ = *wide.two_level;
            wide_scene_ = gpu::WideScene{nullptr, &*two_level_, opaque};
            return;
        }
        if (scene_.bvh == nullptr) return;
        const WideBvh* flat = wide.flat ? wide.flat : &own_wide_.emplace(make_wide(*scene_.bvh));
        wide_scene_ = gpu::WideScene{flat, nullptr, opaque};
    }

    /// Whether `two` holds what the scene was made from: its meshes' primitive counts, and each
    /// instance in its slot with its transform and a mesh in range (a hit it returns is then one of
    /// the scene's primitives in a slot that holds it, which the shading reads); an instance the
    /// TLAS's tree leaves out (of an empty mesh: refused before, helper probe 2026-12-07) has no
    /// slot, and is never hit.
    bool made_from(const TwoLevel& two) const {
        const Tlas& tlas = *two.tlas;
        const std::size_t meshes = scene_.first_triangle.size();
        if (tlas.instances.size() != scene_.instance_slots.size() || two.blases.size() != meshes) return false;
        for (std::size_t k = 0; k < meshes; ++k) {
            const bool last = k + 1 == meshes;
            const std::size_t triangles =
                (last ? scene_.triangles.size() : scene_.first_triangle[k + 1]) - scene_.first_triangle[k];
            const std::size_t spheres =
                (last ? scene_.spheres.size() : scene_.first_sphere[k + 1]) - scene_.first_sphere[k];
            if (two.blases[k].bvh->triangle_count != triangles || two.blases[k].bvh->sphere_count != spheres)
                return false;
        }
        for (std::size_t i = 0; i < tlas.instances.size(); ++i) {
            const std::uint32_t slot = scene_.instance_slots[i];
            if (slot == gpu::NO_INSTANCE) {
                if (!tlas.instances[i].world_box.empty()) return false;
                continue;
            }
            if (slot >= scene_.instances.size() || scene_.instances[slot].tree.w != i) return false;
            const gpu::GpuInstance& g = scene_.instances[slot];
            const float rows[12] = {g.row0.x, g.row0.y, g.row0.z, g.row0.w, g.row1.x, g.row1.y,
                                    g.row1.z, g.row1.w, g.row2.x, g.row2.y, g.row2.z, g.row2.w};
            const Instance& inst = tlas.instances[i];
            const ObjectMap map = object_map(inst.object_to_world, inst.world_to_object);
            if (std::memcmp(rows, map.m.data(), sizeof rows) != 0) return false;
        }
        return true;
    }

    std::string walk_note(const RenderSettings& settings) const {
        if (settings.traversal != Traversal::Wide) return "";
        if (!wide_scene_) return "; two-level without its TLAS: stack walk";
        // short: the Last Render box shows it (a scene with a transparent material: design.md, "The tracer")
        return wide_scene_->opaque ? ", wide walk"
                                   : ", wide walk; shadows through glass or hidden surfaces: stack walk";
    }

    static void note_budgets(RunShared& shared, std::uint64_t budgets) {
        auto n = std::uint32_t(std::min<std::uint64_t>(budgets, 0xffffffffu));
        for (std::uint32_t seen = shared.most_budgets.load();
             n > seen && !shared.most_budgets.compare_exchange_weak(seen, n);) {}
    }

    /// One pixel's samples up to frame.sample_target, in budgets of steps; between budgets the
    /// trace is saved and loaded back (what a dispatch boundary does on the GPU).
    template <class Tracer>
    PixelResult trace_pixel(Tracer& tracer, gpu::uvec2 p, RunShared& shared, const Cancellation* cancel) const {
        typename Tracer::TraceState s = tracer.begin_pixel(p, tracer.samples_done(p), tracer.frame.sample_target);
        for (std::uint32_t budgets = 1;; ++budgets) {
            tracer.trace_steps(s, timings_.steps_per_dispatch);
            if (s.phase >= Tracer::PHASE_DONE) {
                note_budgets(shared, budgets);
                return s.phase == Tracer::PHASE_DONE ? PixelResult::Done : PixelResult::Failed;
            }
            if (cancel && cancel->stop_requested()) return PixelResult::Stopped;
            tracer.save_state(s, 1u);
            s = tracer.load_state();
        }
    }

    /// Rows are handed out one at a time; the calling thread also polls `cancel` (at most every
    /// 20 ms, Cancellation::poll) before pixels 0, kPollPixels, 2 · kPollPixels, ... of each row: poll reads
    /// the clock, and a clock read before each pixel took 5.6% of a wide-traversal frame (atrium,
    /// 1322×784, one thread; perf).
    void trace_rows(const gpu::FrameParams& frame, RunShared& shared, Cancellation* cancel, double* progress,
                    bool caller) {
        if (frame.count_traversal) trace_rows_with<gpu::CpuTracerOf<true>>(frame, shared, cancel, progress, caller);
        else trace_rows_with<gpu::CpuTracerOf<false>>(frame, shared, cancel, progress, caller);
    }

    static constexpr std::uint32_t kPollPixels = 64;

    template <class Tracer>
    void trace_rows_with(const gpu::FrameParams& frame, RunShared& shared, Cancellation* cancel, double* progress,
                         bool caller) {
        Tracer tracer(scene_, frame, overlay_.data(), &sums_, gpu_traversal(settings_.traversal),
                      wide_scene_ ? &*wide_scene_ : nullptr);
        trace_rows_of(tracer, frame, shared, cancel, progress, caller);
        shared.shadow_opaque.fetch_add(tracer.shadow_opaque);
        shared.shadow_glass.fetch_add(tracer.shadow_glass);
        shared.camera_ahead.fetch_add(tracer.camera_ahead);
    }

    template <class Tracer>
    void trace_rows_of(Tracer& tracer, const gpu::FrameParams& frame, RunShared& shared, Cancellation* cancel,
                       double* progress, bool caller) {
        const double pixels = double(frame.width) * frame.height;
        // a render without the cost traces a flat scene's camera rays ahead, a run of pixels at a
        // time, eight together where they run together (cpu_tracer.h trace_camera_rays)
        const bool ahead = !settings_.keep_cost && tracer.traces_camera_rays_ahead();
        const std::uint32_t run =
            CameraPackets::run_pixels(frame.sample_target - std::min(frame.sample_target, samples_done_));
        for (std::uint32_t y; (y = shared.next_row.fetch_add(1)) < frame.height;) {
            for (std::uint32_t x = 0, run_end = 0; x < frame.width; ++x) {
                if (caller && cancel && x % kPollPixels == 0) {
                    if (progress) *progress = double(shared.pixels_done.load()) / pixels;
                    cancel->poll();
                }
                if ((cancel && cancel->stop_requested()) || shared.abort.load()) return;
                if (ahead && x == run_end) {
                    run_end = std::min(frame.width, x + run);
                    tracer.trace_camera_rays(y, x, run_end);
                }
                PixelResult r = trace_pixel(tracer, gpu::uvec2(x, y), shared, cancel);
                if (r == PixelResult::Done) shared.pixels_done.fetch_add(1);
                if (r == PixelResult::Failed) {
                    shared.pixels_failed.fetch_add(1);
                    shared.abort.store(true);
                }
            }
        }
    }

    /// The calling thread traces rows too; when they run out it keeps polling `cancel` until the
    /// other threads are done, so Ctrl-C stops a render promptly whichever thread holds the work.
    /// The caller's check runs once before any thread starts: the other threads could otherwise
    /// take every row before the calling thread reaches its first pixel, and a small image then
    /// finished without one call of the check (a progress callback never called, a cancel not
    /// honoured: test_render_api's cancel failed so under load).
    void run_threads(const gpu::FrameParams& frame, RunShared& shared, Cancellation* cancel, double* progress) {
        if (cancel) {
            if (progress) *progress = 0.0;
            if (cancel->poll()) return;
        }
        auto work = [&](bool caller) {
            try {
                trace_rows(frame, shared, cancel, progress, caller);
            } catch (...) {  // never let an exception escape a thread: rethrown by run()
                std::lock_guard<std::mutex> lock(shared.error_mutex);
                if (!shared.error) shared.error = std::current_exception();
                shared.abort.store(true);
            }
            if (shared.workers_left.fetch_sub(1) == 1) {
                std::lock_guard<std::mutex> lock(shared.done_mutex);
                shared.done.notify_all();
            }
        };
        const std::uint32_t n = std::max(1u, std::min(threads_, frame.height));
        shared.workers_left.store(n);
        std::vector<std::thread> pool;
        for (std::uint32_t t = 1; t < n; ++t) pool.emplace_back(work, false);
        work(true);
        // polled every 5 ms, and woken as the last worker ends (a sleep of 5 ms made every
        // render on several threads take at least that: an 8 × 8 frame 0.05 ms on one thread,
        // 5.2 on two)
        while (cancel && shared.workers_left.load() > 0) {
            if (progress) *progress = double(shared.pixels_done.load()) / (double(frame.width) * frame.height);
            cancel->poll();
            std::unique_lock<std::mutex> lock(shared.done_mutex);
            shared.done.wait_for(lock, std::chrono::milliseconds(5), [&] { return shared.workers_left.load() == 0; });
        }
        for (auto& t : pool) t.join();
    }

    const RenderScene& scene_;
    gpu::FrameParams frame_;
    std::uint32_t threads_;
    std::optional<WideBvh> own_wide_;
    std::optional<TwoLevel> two_level_;
    std::optional<gpu::WideScene> wide_scene_;
    std::vector<gpu::vec4> overlay_;
    PixelSums sums_;
};

}  // namespace

std::unique_ptr<RenderJob> start_cpu(const RenderScene& scene, const RenderSettings& settings, std::uint32_t threads,
                                     const WideTrees& wide) {
    validate(settings);
    check_render_scene(scene);
    return std::make_unique<CpuRenderJob>(scene, settings, threads, wide);
}

RenderTimings render_cpu(const RenderScene& scene, const RenderSettings& settings, const RenderImages& out,
                         std::uint32_t threads, Cancellation* cancel) {
    const auto start = Clock::now();
    std::unique_ptr<RenderJob> job = start_cpu(scene, settings, threads);
    job->run(job->samples_per_pixel(), cancel);
    job->resolve(out);
    RenderTimings t = job->timings();
    t.total_ms = ms_since(start);
    return t;
}

}  // namespace bvhlab
