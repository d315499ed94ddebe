// vulkan_renderer.h — the report's renderer on any Vulkan device (report §3.2, Figure 2): the
// overlay pass (graphics pipeline, instanced LINE_LIST) and the trace pass (compute, the shared
// tracer code in shaders/tracer/, in bounded dispatches), headless, read back into float arrays.
// On machines without a GPU it runs on Mesa's lavapipe.
#pragma once
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "bvhlab/render.h"

namespace bvhlab {

/// No Vulkan loader, no driver, or no usable device; the message says what to install.
struct VulkanUnavailable : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct VulkanOptions {
    /// Device to use: an index into the enumeration or a substring of the device name. Empty:
    /// the environment variable BVHLAB_VULKAN_DEVICE, else the first discrete GPU, else
    /// integrated, else virtual, else a CPU driver (lavapipe).
    std::string device;
    /// Enable VK_LAYER_KHRONOS_validation (also when BVHLAB_VULKAN_VALIDATION=1) and collect its
    /// messages; throws VulkanUnavailable if the layer is asked for but not installed.
    bool validation = false;
    /// Upload through a staging buffer, and read each frame back through the readback buffer,
    /// even where device memory is host-visible (tests the path real GPUs take).
    bool force_staging = false;
};

/// Is the Vulkan loader present (cheap; does not create an instance)?
bool vulkan_loader_available();

namespace vk {
struct RendererCore;
}

/// Safe to share between threads: every operation takes the renderer's lock (one render at a
/// time per renderer; Vulkan queues are not thread-safe), and a RenderJob keeps what it uses alive.
class VulkanRenderer {
public:
    explicit VulkanRenderer(const VulkanOptions& options = {});
    ~VulkanRenderer();
    VulkanRenderer(const VulkanRenderer&) = delete;
    VulkanRenderer& operator=(const VulkanRenderer&) = delete;

    std::string device_name() const;
    std::string device_type() const;  ///< "discrete", "integrated", "virtual", "cpu" or "other"
    /// The largest image side: the device's limit, at most kMaxImageDimension.
    std::uint32_t max_image_dimension() const;
    /// Whether the overlay's lines are drawn as Bresenham lines (VK_EXT/KHR_line_rasterization),
    /// the CPU reference's rule of one pixel a column or row; else the device's default rule.
    bool bresenham_lines() const;
    /// The widest overlay line the device draws, in whole pixels (its lineWidthRange; 1 without
    /// wideLines): RenderSettings::line_width, rounded, is clamped to it.
    float max_line_width() const;

    /// Copies the scene to the device for the renders started after it; returns milliseconds. The
    /// RenderScene may be destroyed afterwards.
    double upload(const RenderScene& scene);

    /// A render in sample passes of the scene uploaded last (render.h). Throws
    /// std::invalid_argument for bad settings (validate(settings, max_image_dimension())) and for
    /// Traversal::Wide (the CPU tracer's).
    std::unique_ptr<RenderJob> start(const RenderSettings& settings);

    /// start, every sample, resolve: overlay pass (if settings.overlay), trace pass in bounded
    /// dispatches, readback. Throws Cancelled when `cancel` says stop, RenderIncomplete when a pixel
    /// cannot finish.
    RenderTimings render(const RenderSettings& settings, const RenderImages& out, Cancellation* cancel = nullptr);

    /// Validation-layer messages (warnings and errors) since the last call; clears them.
    std::vector<std::string> take_validation_messages();
    /// Validation errors since construction.
    std::uint32_t validation_error_count() const;

private:
    std::shared_ptr<vk::RendererCore> core_;
};

}  // namespace bvhlab
