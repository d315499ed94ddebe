// pixel_ray.cpp — a pixel's primary ray through the tracer's own camera code (cpu_tracer.h).
#include "bvhlab/pixel_ray.h"

#include <stdexcept>
#include <string>

#include "cpu_tracer.h"

namespace bvhlab {

Ray pixel_ray(const RenderScene& scene, const RenderSettings& settings, std::uint32_t x, std::uint32_t y,
              std::uint32_t sample_index) {
    validate(settings);
    check_render_scene(scene);
    if (x >= settings.width || y >= settings.height)
        throw std::invalid_argument("pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") lies outside the " +
                                    std::to_string(settings.width) + "×" + std::to_string(settings.height) + " image");
    const std::uint32_t samples = settings.samples_per_axis * settings.samples_per_axis;
    if (sample_index >= samples)
        throw std::invalid_argument("sample " + std::to_string(sample_index) + " does not exist: a pixel has " +
                                    std::to_string(samples) + " samples");
    const gpu::FrameParams frame = make_frame_params(scene, settings);
    gpu::CpuTracer tracer(scene, frame, nullptr, nullptr, gpu_traversal(settings.traversal));
    const auto task = tracer.camera_ray(gpu::uvec2(x, y), sample_index);
    if (!tracer.has_ray(task))
        throw std::invalid_argument("pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                    ") has no ray (outside the fisheye's frame)");
    // the span start_closest (shade.glsl) gives a primary ray's query, without the overlay's lines
    const gpu::vec2 span = tracer.query_span(task, gpu::vec4(0.0f));
    Ray ray;
    ray.origin = {task.origin.x, task.origin.y, task.origin.z};
    ray.dir = {task.dir.x, task.dir.y, task.dir.z};
    ray.tmin = span.x, ray.tmax = span.y;
    return ray;
}

}  // namespace bvhlab
