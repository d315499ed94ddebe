// VulkanRenderer when bvhlab was built without the Vulkan backend (BVHLAB_VULKAN=OFF: glslc or the
// Vulkan headers were missing at configure time): constructing one says so.
#include "bvhlab/vulkan_renderer.h"

namespace bvhlab {

namespace vk {
struct RendererCore {};
}  // namespace vk

bool vulkan_loader_available() { return false; }

VulkanRenderer::VulkanRenderer(const VulkanOptions&) {
    throw VulkanUnavailable(
        "bvhlab was built without Vulkan support: install glslc and libvulkan-dev, then rebuild with BVHLAB_VULKAN=ON");
}
VulkanRenderer::~VulkanRenderer() = default;

// Unreachable: no object can exist.
std::string VulkanRenderer::device_name() const { return {}; }
std::string VulkanRenderer::device_type() const { return {}; }
std::uint32_t VulkanRenderer::max_image_dimension() const { return 0; }
double VulkanRenderer::upload(const RenderScene&) { return 0; }
std::unique_ptr<RenderJob> VulkanRenderer::start(const RenderSettings&) { return nullptr; }
RenderTimings VulkanRenderer::render(const RenderSettings&, const RenderImages&, Cancellation*) { return {}; }
std::vector<std::string> VulkanRenderer::take_validation_messages() { return {}; }
std::uint32_t VulkanRenderer::validation_error_count() const { return 0; }

}  // namespace bvhlab
