// vk_commands.h — one command buffer and a fence: record, submit, wait, timed as a whole (every
// pass is its own submission: timestamps inside a dynamic-rendering pass are meaningless on
// lavapipe); and the synchronization2 barriers the passes use.
#pragma once
#include <chrono>

#include "vk_device.h"

namespace bvhlab::vk {

class CommandRunner {
public:
    explicit CommandRunner(const Device& device);

    /// Records `record(VkCommandBuffer)`, submits and waits; returns the milliseconds from the
    /// start of recording until the work is done.
    template <class Record>
    double run(Record&& record) {
        begin();
        record(command_buffer_);
        return submit_and_wait();
    }

private:
    void begin();
    double submit_and_wait();

    const Device& device_;
    OwnedCommandPool pool_;
    VkCommandBuffer command_buffer_ = VK_NULL_HANDLE;  // freed with the pool
    OwnedFence fence_;
    std::chrono::steady_clock::time_point start_;
};

/// A stage and access scope, with the layout an image is in there.
struct ImageState {
    VkPipelineStageFlags2 stage;
    VkAccessFlags2 access;
    VkImageLayout layout;
};

/// Whole-image layout transition and dependency between two uses.
void image_barrier(const Functions& fn, VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, ImageState from,
                   ImageState to);

/// Global memory dependency (buffers), e.g. transfer writes → shader reads, copy → host read.
void memory_barrier(const Functions& fn, VkCommandBuffer cmd, VkPipelineStageFlags2 src_stage,
                    VkAccessFlags2 src_access, VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access);

}  // namespace bvhlab::vk
