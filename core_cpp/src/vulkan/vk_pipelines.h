// vk_pipelines.h — the two pipelines of a frame (report §3.2, Figure 2): the overlay graphics
// pipeline (§3.3) and the trace compute pipeline, once per traversal variant (§3.1, specialization
// constant 0). They share one descriptor set layout — the FrameParams buffer + the rgba32f image —
// and one pipeline layout.
#pragma once
#include <cstdint>

#include "vk_device.h"

namespace bvhlab::vk {

/// The image both passes write (overlay: rgb + camera distance; trace: final colour) and the
/// overlay's depth buffer.
inline constexpr VkFormat kColorFormat = VK_FORMAT_R32G32B32A32_SFLOAT;
inline constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;

class Pipelines {
public:
    explicit Pipelines(const Device& device);

    VkDescriptorSetLayout set_layout() const { return set_layout_.get(); }
    VkPipelineLayout layout() const { return layout_.get(); }
    VkPipeline trace(std::uint32_t traversal) const { return trace_[traversal].get(); }
    VkPipeline overlay() const { return overlay_.get(); }

private:
    OwnedSetLayout set_layout_;
    OwnedPipelineLayout layout_;
    OwnedPipeline trace_[2];  ///< by gpu::TRAVERSAL_STACK / TRAVERSAL_STACKLESS
    OwnedPipeline overlay_;
};

/// Instanced LINE_LIST into kColorFormat with a kDepthFormat depth test (LESS), dynamic rendering,
/// no vertex buffers (overlay.vert builds the edges from gl_VertexIndex and the box array);
/// viewport, scissor and line width are dynamic.
OwnedPipeline create_overlay_pipeline(const Device& device, VkPipelineLayout layout);

}  // namespace bvhlab::vk
