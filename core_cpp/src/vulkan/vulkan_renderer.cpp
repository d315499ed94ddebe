// VulkanRenderer (bvhlab/vulkan_renderer.h): the report's renderer (§3.2, Figure 2) on any Vulkan
// 1.3 device — overlay pass, trace pass in bounded dispatches, readback — assembled from the pieces
// in this folder; the rendering itself is a RenderJob (vk_trace_job.cpp).
#include "bvhlab/vulkan_renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "vk_renderer_core.h"

namespace bvhlab {
namespace vk {
namespace {

bool validation_requested(const VulkanOptions& options) {
    const char* env = std::getenv("BVHLAB_VULKAN_VALIDATION");
    return options.validation || (env && *env && std::strcmp(env, "0") != 0);  // as python/bvhlab/render.py
}

}  // namespace

RendererCore::RendererCore(const VulkanOptions& options)
    : force_staging(options.force_staging),
      instance(fn, validation_requested(options), log),
      device(fn, select_physical_device(fn, instance.handle(), options.device)),
      runner(device),
      pipelines(device),
      bindings(device, pipelines.set_layout()),
      slots(device),
      scene(std::make_shared<const SceneBuffers>(device, runner, RenderScene{}, force_staging)) {
}  // before upload(): sky

void RendererCore::ensure_targets(std::uint32_t width, std::uint32_t height) {
    if (targets && targets->width == width && targets->height == height) return;
    overlay_job = 0;  // new targets hold no job's overlay (also where making them fails)
    targets.reset();  // free the old size first
    targets.emplace(device, width, height);
    bindings.bind_overlay(targets->color.view());
}

float RendererCore::max_line_width() const {
    const PhysicalDevice& p = device.physical();
    return p.wide_lines ? std::max(1.0f, std::floor(p.properties.limits.lineWidthRange[1])) : 1.0f;
}

float RendererCore::line_width(const RenderSettings& settings) const {
    return std::min(whole_line_width(settings.line_width), max_line_width());
}

std::uint32_t RendererCore::next_stamp() {
    if (++stamp == 0) {  // wrapped: no slot may still carry a stamp that comes round again
        stamp = 1;
        runner.run([&](VkCommandBuffer cmd) { record_fill(fn, cmd, slots.state(), 0u); });
    }
    return stamp;
}

}  // namespace vk

VulkanRenderer::VulkanRenderer(const VulkanOptions& options) : core_(std::make_shared<vk::RendererCore>(options)) {}
VulkanRenderer::~VulkanRenderer() = default;

std::string VulkanRenderer::device_name() const { return core_->device.physical().name(); }
std::string VulkanRenderer::device_type() const { return core_->device.physical().type_name(); }
bool VulkanRenderer::bresenham_lines() const { return core_->device.physical().bresenham_lines; }

float VulkanRenderer::max_line_width() const { return core_->max_line_width(); }
std::uint32_t VulkanRenderer::max_image_dimension() const {
    return std::min(core_->device.physical().properties.limits.maxImageDimension2D, kMaxImageDimension);
}

double VulkanRenderer::upload(const RenderScene& scene) {
    const auto start = std::chrono::steady_clock::now();
    check_render_scene(scene);  // before the scene in place is freed: bad input loses nothing
    const auto lock = lock_in_slices(core_->mutex);
    vk::RendererCore& c = *core_;
    c.scene.reset();  // free the old scene (unless a job still holds it) before allocating the new one
    try {
        c.scene = std::make_shared<const vk::SceneBuffers>(c.device, c.runner, scene, c.force_staging);
    } catch (...) {
        c.scene = std::make_shared<const vk::SceneBuffers>(c.device, c.runner, RenderScene{},
                                                           c.force_staging);  // usable: sky
        throw;
    }
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

std::unique_ptr<RenderJob> VulkanRenderer::start(const RenderSettings& settings) {
    validate(settings, max_image_dimension());
    if (settings.traversal == Traversal::Wide)
        throw std::invalid_argument("the Vulkan tracer walks 'stack' or 'stackless'; 'wide' is the CPU tracer's");
    std::shared_ptr<const vk::SceneBuffers> scene;
    {
        const auto lock = lock_in_slices(core_->mutex);
        scene = core_->scene;
    }
    return vk::start_vulkan_job(core_, std::move(scene), settings);
}

RenderTimings VulkanRenderer::render(const RenderSettings& settings, const RenderImages& out, Cancellation* cancel) {
    const auto start_time = std::chrono::steady_clock::now();
    std::unique_ptr<RenderJob> job = start(settings);
    job->run(job->samples_per_pixel(), cancel);
    job->resolve(out);
    RenderTimings t = job->timings();
    t.total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_time).count();
    return t;
}

std::vector<std::string> VulkanRenderer::take_validation_messages() { return core_->log.take(); }
std::uint32_t VulkanRenderer::validation_error_count() const { return core_->log.error_count(); }

}  // namespace bvhlab
