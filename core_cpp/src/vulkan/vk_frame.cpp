// Frame targets (colour, depth, readback) and the descriptor set with the FrameParams buffer.
#include "vk_frame.h"

#include "vk_check.h"
#include "vk_pipelines.h"

namespace bvhlab::vk {

FrameTargets::FrameTargets(const Device& device, std::uint32_t width, std::uint32_t height)
    : width(width),
      height(height),
      color(device, {width, height}, kColorFormat,
            VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                VK_IMAGE_USAGE_TRANSFER_DST_BIT,
            VK_IMAGE_ASPECT_COLOR_BIT),
      depth(device, {width, height}, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT),
      readback(device, VkDeviceSize(width) * height * sizeof(gpu::vec4), VK_BUFFER_USAGE_TRANSFER_DST_BIT,
               MemoryUse::Readback) {}

FrameBindings::FrameBindings(const Device& device, VkDescriptorSetLayout layout)
    : device_(device), params_(device, sizeof(gpu::FrameParams), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::PerFrame) {
    const Functions& fn = device.fn();
    VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1}, {VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1}};
    VkDescriptorPoolCreateInfo pool{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pool.maxSets = 1;
    pool.poolSizeCount = 2;
    pool.pPoolSizes = sizes;
    VkDescriptorPool pool_handle = VK_NULL_HANDLE;
    VK_CHECK(fn.vkCreateDescriptorPool(device.handle(), &pool, nullptr, &pool_handle));
    pool_ = OwnedDescriptorPool(device, pool_handle);
    VkDescriptorSetAllocateInfo allocate{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    allocate.descriptorPool = pool_handle;
    allocate.descriptorSetCount = 1;
    allocate.pSetLayouts = &layout;
    VK_CHECK(fn.vkAllocateDescriptorSets(device.handle(), &allocate, &set_));
    VkDescriptorBufferInfo buffer{params_.handle(), 0, sizeof(gpu::FrameParams)};
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = set_;
    write.dstBinding = gpu::BINDING_FRAME;
    write.descriptorCount = 1;
    write.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    write.pBufferInfo = &buffer;
    fn.vkUpdateDescriptorSets(device.handle(), 1, &write, 0, nullptr);
}

void FrameBindings::write_params(const gpu::FrameParams& frame) { params_.write(&frame, sizeof(frame)); }

void FrameBindings::bind_image(VkImageView color) {
    VkDescriptorImageInfo image{VK_NULL_HANDLE, color, VK_IMAGE_LAYOUT_GENERAL};  // the trace pass's layout
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = set_;
    write.dstBinding = gpu::BINDING_IMAGE;
    write.descriptorCount = 1;
    write.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
    write.pImageInfo = &image;
    device_.fn().vkUpdateDescriptorSets(device_.handle(), 1, &write, 0, nullptr);
}

}  // namespace bvhlab::vk
