// VulkanRenderer (bvhlab/vulkan_renderer.h): the report's renderer (§3.2, Figure 2) on any Vulkan
// 1.3 device — overlay pass, trace pass, readback — assembled from the pieces in this folder.
#include "bvhlab/vulkan_renderer.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <optional>

#include "vk_commands.h"
#include "vk_device.h"
#include "vk_frame.h"
#include "vk_instance.h"
#include "vk_passes.h"
#include "vk_pipelines.h"
#include "vk_scene.h"

namespace bvhlab {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) { return std::chrono::duration<double, std::milli>(Clock::now() - start).count(); }

bool validation_requested(const VulkanOptions& options) {
    const char* env = std::getenv("BVHLAB_VULKAN_VALIDATION");
    return options.validation || (env && *env && std::strcmp(env, "0") != 0);  // as python/bvhlab/render.py
}

}  // namespace

struct VulkanRenderer::Impl {
    explicit Impl(const VulkanOptions& options)
        : force_staging(options.force_staging),
          instance(fn, validation_requested(options), log),
          device(fn, vk::select_physical_device(fn, instance.handle(), options.device)),
          runner(device),
          pipelines(device),
          bindings(device, pipelines.set_layout()),
          scene(std::in_place, device, runner, RenderScene{}, force_staging) {}  // render() before upload(): sky

    // Every submission is waited for, but an exception may leave one in flight.
    ~Impl() { (void)fn.vkDeviceWaitIdle(device.handle()); }

    void ensure_targets(std::uint32_t width, std::uint32_t height) {
        if (targets && targets->width == width && targets->height == height) return;
        targets.reset();  // free the old size first
        targets.emplace(device, width, height);
        bindings.bind_image(targets->color.view());
    }

    /// settings.line_width where the device draws wide lines, else 1 (the only width allowed).
    float line_width(const RenderSettings& settings) const {
        const vk::PhysicalDevice& p = device.physical();
        if (!p.wide_lines) return 1.0f;
        return std::clamp(settings.line_width, p.properties.limits.lineWidthRange[0], p.properties.limits.lineWidthRange[1]);
    }

    // Declared in creation order: destroyed in reverse.
    const bool force_staging;
    vk::Functions fn;
    vk::ValidationLog log;
    vk::Instance instance;
    vk::Device device;
    vk::CommandRunner runner;
    vk::Pipelines pipelines;
    vk::FrameBindings bindings;
    std::optional<vk::SceneBuffers> scene;
    std::optional<vk::FrameTargets> targets;
};

VulkanRenderer::VulkanRenderer(const VulkanOptions& options) : impl_(std::make_unique<Impl>(options)) {}
VulkanRenderer::~VulkanRenderer() = default;

std::string VulkanRenderer::device_name() const { return impl_->device.physical().name(); }
std::string VulkanRenderer::device_type() const { return impl_->device.physical().type_name(); }
std::uint32_t VulkanRenderer::max_image_dimension() const {
    return impl_->device.physical().properties.limits.maxImageDimension2D;
}

double VulkanRenderer::upload(const RenderScene& scene) {
    const auto start = Clock::now();
    Impl& r = *impl_;
    r.scene.reset();  // free the old scene before allocating the new one
    try {
        r.scene.emplace(r.device, r.runner, scene, r.force_staging);
    } catch (...) {
        r.scene.emplace(r.device, r.runner, RenderScene{}, r.force_staging);  // stay usable: sky
        throw;
    }
    return ms_since(start);
}

RenderTimings VulkanRenderer::render(const RenderSettings& settings, float* rgba) {
    validate(settings, max_image_dimension());
    Impl& r = *impl_;
    const auto start = Clock::now();
    const gpu::FrameParams frame = r.scene->frame_params(settings);
    r.bindings.write_params(frame);  // the previous frame is done: every pass waits for its fence
    r.ensure_targets(settings.width, settings.height);
    const vk::PassContext pass{r.fn, r.pipelines, r.bindings.set(), *r.targets};
    RenderTimings t;
    t.device = device_name();
    t.overlay_ms = r.runner.run([&](VkCommandBuffer cmd) {
        if (settings.overlay) vk::record_overlay(pass, cmd, frame, r.line_width(settings));
        else vk::record_clear(pass, cmd);
    });
    t.trace_ms = r.runner.run([&](VkCommandBuffer cmd) { vk::record_trace(pass, cmd, settings.traversal); });
    const auto readback_start = Clock::now();
    r.runner.run([&](VkCommandBuffer cmd) { vk::record_readback(pass, cmd); });
    r.targets->readback.read(rgba, std::size_t(settings.width) * settings.height * sizeof(gpu::vec4));
    t.readback_ms = ms_since(readback_start);
    t.total_ms = ms_since(start);
    return t;
}

std::vector<std::string> VulkanRenderer::take_validation_messages() { return impl_->log.take(); }
std::uint32_t VulkanRenderer::validation_error_count() const { return impl_->log.error_count(); }

}  // namespace bvhlab
