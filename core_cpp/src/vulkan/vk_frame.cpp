// Frame targets, the descriptor set with the FrameParams buffer, trace slots and pixel sums.
#include "vk_frame.h"

#include <algorithm>
#include <cstring>

#include "vk_check.h"
#include "vk_pipelines.h"

namespace bvhlab::vk {
namespace {

/// The (low, high) words of a device address, as the shaders' uvec2 buffer references read them.
gpu::uvec2 words(VkDeviceAddress a) { return {std::uint32_t(a), std::uint32_t(a >> 32)}; }

constexpr VkBufferUsageFlags kShaderArray = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                                            VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                            VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT;

Buffer shader_array(const Device& device, VkDeviceSize bytes) {
    return Buffer(device, std::max<VkDeviceSize>(bytes, 16), kShaderArray, MemoryUse::DeviceLocal);
}

}  // namespace

FrameTargets::FrameTargets(const Device& device, std::uint32_t width, std::uint32_t height)
    : width(width),
      height(height),
      color(device, {width, height}, kColorFormat,
            VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
            VK_IMAGE_ASPECT_COLOR_BIT),
      depth(device, {width, height}, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
            VK_IMAGE_ASPECT_DEPTH_BIT) {}

FrameBindings::FrameBindings(const Device& device, VkDescriptorSetLayout layout)
    : device_(device),
      params_(device, sizeof(gpu::FrameParams), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::PerFrame) {
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

void FrameBindings::bind_overlay(VkImageView color) {
    VkDescriptorImageInfo image{VK_NULL_HANDLE, color, VK_IMAGE_LAYOUT_GENERAL};  // the trace pass's layout
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = set_;
    write.dstBinding = gpu::BINDING_OVERLAY;
    write.descriptorCount = 1;
    write.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
    write.pImageInfo = &image;
    device_.fn().vkUpdateDescriptorSets(device_.handle(), 1, &write, 0, nullptr);
}

TraceSlots::TraceSlots(const Device& device)
    : device_(device),
      counters_(device, 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                MemoryUse::PerFrame) {
    reset_counters();
}

bool TraceSlots::reserve(std::uint32_t slots, std::uint32_t ray_entries, std::uint32_t node_entries) {
    if (slots <= slots_ && ray_entries <= ray_entries_ && node_entries <= node_entries_) return false;
    slots_ = std::max(slots, slots_);
    ray_entries_ = std::max(ray_entries, ray_entries_);
    node_entries_ = std::max(node_entries, node_entries_);
    state_ = Buffer();  // free the old memory first
    rays_ = Buffer();
    nodes_ = Buffer();
    state_ = shader_array(device_, VkDeviceSize(slots_) * gpu::STATE_WORDS * sizeof(gpu::uvec4));
    rays_ = shader_array(device_, VkDeviceSize(slots_) * 3 * ray_entries_ * sizeof(gpu::uvec4));
    nodes_ = shader_array(device_, VkDeviceSize(slots_) * node_entries_ * sizeof(gpu::uvec2));
    return true;
}

void TraceSlots::address(gpu::FrameParams& frame) const {
    frame.addr.slot_state = words(state_.address());
    frame.addr.slot_rays = words(rays_.address());
    frame.addr.slot_nodes = words(nodes_.address());
    frame.addr.counters = words(counters_.address());
    // the stacks are laid out for the reserved sizes (trace.comp indexes slot · entries + k)
    frame.ray_stack_entries = ray_entries_;
    frame.node_stack_entries = node_entries_;
}

void TraceSlots::reset_counters() {
    const std::uint32_t zero[2] = {0, 0};
    counters_.write(zero, sizeof(zero));
}

std::uint32_t TraceSlots::unfinished() const {
    std::uint32_t n[2] = {0, 0};
    counters_.read(n, sizeof(n));
    return n[0];
}

std::uint32_t TraceSlots::failed() const {
    std::uint32_t n[2] = {0, 0};
    counters_.read(n, sizeof(n));
    return n[1];
}

SumBuffers::SumBuffers(const Device& device, std::size_t pixels, bool counters, bool covered_samples)
    : pixels(pixels),
      color(shader_array(device, pixels * sizeof(gpu::vec4))),
      depth(shader_array(device, pixels * sizeof(float))),
      samples(shader_array(device, pixels * sizeof(std::uint32_t))) {
    if (counters) counts = shader_array(device, pixels * sizeof(gpu::TraversalCounts));
    if (covered_samples) covered = shader_array(device, pixels * sizeof(std::uint32_t));
}

void SumBuffers::address(gpu::FrameParams& frame) const {
    frame.addr.accum_color = words(color.address());
    frame.addr.accum_depth = words(depth.address());
    frame.addr.accum_samples = words(samples.address());
    if (counts.size()) frame.addr.accum_counts = words(counts.address());
    if (covered.size()) frame.addr.accum_covered = words(covered.address());
}

}  // namespace bvhlab::vk
