// One-shot, timed submissions and the synchronization2 barrier helpers.
#include "vk_commands.h"

#include <cstdint>

#include "vk_check.h"

namespace bvhlab::vk {

CommandRunner::CommandRunner(const Device& device) : device_(device) {
    const Functions& fn = device.fn();
    VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool.queueFamilyIndex = device.physical().queue_family;
    VkCommandPool pool_handle = VK_NULL_HANDLE;
    VK_CHECK(fn.vkCreateCommandPool(device.handle(), &pool, nullptr, &pool_handle));
    pool_ = OwnedCommandPool(device, pool_handle);
    VkCommandBufferAllocateInfo allocate{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    allocate.commandPool = pool_handle;
    allocate.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    allocate.commandBufferCount = 1;
    VK_CHECK(fn.vkAllocateCommandBuffers(device.handle(), &allocate, &command_buffer_));
    VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence_handle = VK_NULL_HANDLE;
    VK_CHECK(fn.vkCreateFence(device.handle(), &fence, nullptr, &fence_handle));
    fence_ = OwnedFence(device, fence_handle);
}

void CommandRunner::begin() {
    start_ = std::chrono::steady_clock::now();
    // Explicit reset: also recovers a buffer left recording by an exception in `record`.
    VK_CHECK(device_.fn().vkResetCommandBuffer(command_buffer_, 0));
    VkCommandBufferBeginInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    info.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    VK_CHECK(device_.fn().vkBeginCommandBuffer(command_buffer_, &info));
}

double CommandRunner::submit_and_wait() {
    const Functions& fn = device_.fn();
    VK_CHECK(fn.vkEndCommandBuffer(command_buffer_));
    VkCommandBufferSubmitInfo command{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
    command.commandBuffer = command_buffer_;
    VkSubmitInfo2 submit{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
    submit.commandBufferInfoCount = 1;
    submit.pCommandBufferInfos = &command;
    VkFence fence = fence_.get();
    VK_CHECK(fn.vkQueueSubmit2(device_.queue(), 1, &submit, fence));
    VK_CHECK(fn.vkWaitForFences(device_.handle(), 1, &fence, VK_TRUE, UINT64_MAX));
    VK_CHECK(fn.vkResetFences(device_.handle(), 1, &fence));
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
}

void image_barrier(const Functions& fn, VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, ImageState from,
                   ImageState to) {
    VkImageMemoryBarrier2 barrier{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
    barrier.srcStageMask = from.stage;
    barrier.srcAccessMask = from.access;
    barrier.dstStageMask = to.stage;
    barrier.dstAccessMask = to.access;
    barrier.oldLayout = from.layout;
    barrier.newLayout = to.layout;
    barrier.srcQueueFamilyIndex = barrier.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    barrier.image = image;
    barrier.subresourceRange = {aspect, 0, 1, 0, 1};
    VkDependencyInfo dependency{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dependency.imageMemoryBarrierCount = 1;
    dependency.pImageMemoryBarriers = &barrier;
    fn.vkCmdPipelineBarrier2(cmd, &dependency);
}

void memory_barrier(const Functions& fn, VkCommandBuffer cmd, VkPipelineStageFlags2 src_stage,
                    VkAccessFlags2 src_access, VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access) {
    VkMemoryBarrier2 barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
    barrier.srcStageMask = src_stage;
    barrier.srcAccessMask = src_access;
    barrier.dstStageMask = dst_stage;
    barrier.dstAccessMask = dst_access;
    VkDependencyInfo dependency{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dependency.memoryBarrierCount = 1;
    dependency.pMemoryBarriers = &barrier;
    fn.vkCmdPipelineBarrier2(cmd, &dependency);
}

}  // namespace bvhlab::vk
