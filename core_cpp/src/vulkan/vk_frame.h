// vk_frame.h — what a frame renders into and reads: the size-dependent targets (recreated only when
// the size changes) and the FrameParams buffer with the one descriptor set both pipelines use.
#pragma once
#include <cstdint>

#include "gpu_types.h"
#include "vk_memory.h"

namespace bvhlab::vk {

struct FrameTargets {
    FrameTargets(const Device& device, std::uint32_t width, std::uint32_t height);

    std::uint32_t width, height;
    Image color;      ///< rgba32f: the overlay's lines, then the traced colour (report §3.2)
    Image depth;      ///< D32, the overlay's depth test
    Buffer readback;  ///< host-visible copy of `color`, row 0 at the top
};

class FrameBindings {
public:
    FrameBindings(const Device& device, VkDescriptorSetLayout layout);

    void write_params(const gpu::FrameParams& frame);  ///< only while no frame is in flight
    void bind_image(VkImageView color);                ///< after the targets change
    VkDescriptorSet set() const { return set_; }

private:
    const Device& device_;
    /// FrameParams, a storage buffer rather than a uniform one: Mesa 22.3's lavapipe recompiles,
    /// and leaks, every shader whose branches read uniform-buffer values, at every submission.
    Buffer params_;
    OwnedDescriptorPool pool_;
    VkDescriptorSet set_ = VK_NULL_HANDLE;  // freed with the pool
};

}  // namespace bvhlab::vk
