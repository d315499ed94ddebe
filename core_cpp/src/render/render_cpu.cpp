// The CPU reference renderer: the overlay pass, then every pixel through the shared tracer code,
// rows handed out to threads a few at a time.
#include <atomic>
#include <chrono>
#include <thread>

#include "cpu_tracer.h"
#include "overlay_cpu.h"

namespace bvhlab {

RenderTimings render_cpu(const RenderScene& scene, const RenderSettings& settings, float* rgba, std::uint32_t threads) {
    validate(settings);
    using Clock = std::chrono::steady_clock;
    auto ms = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
    RenderTimings timings;
    timings.device = "CPU reference (" + std::to_string(threads ? threads : std::thread::hardware_concurrency()) + " threads)";
    auto start = Clock::now();
    const gpu::FrameParams frame = make_frame_params(scene, settings);
    std::vector<gpu::vec4> overlay = rasterize_overlay(scene, settings, frame);
    auto overlay_done = Clock::now();

    std::atomic<std::uint32_t> next_row{0};
    auto worker = [&] {
        gpu::CpuTracer tracer(scene, frame, overlay.data(), settings.traversal);
        for (std::uint32_t y; (y = next_row.fetch_add(1)) < settings.height;) {
            for (std::uint32_t x = 0; x < settings.width; ++x) {
                gpu::vec4 c = tracer.trace_pixel(gpu::uvec2(x, y));
                float* out = rgba + 4 * (std::size_t(y) * settings.width + x);
                out[0] = c.x, out[1] = c.y, out[2] = c.z, out[3] = c.w;
            }
        }
    };
    std::uint32_t n = threads ? threads : std::max(1u, std::thread::hardware_concurrency());
    std::vector<std::thread> pool;
    for (std::uint32_t t = 1; t < n; ++t) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
    auto end = Clock::now();
    timings.overlay_ms = ms(start, overlay_done);
    timings.trace_ms = ms(overlay_done, end);
    timings.total_ms = ms(start, end);
    return timings;
}

}  // namespace bvhlab
