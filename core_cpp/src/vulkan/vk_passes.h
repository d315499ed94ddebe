// vk_passes.h — the commands of a frame (report §3.2, Figure 2), one submission each so each is
// timed whole: the overlay pass (or a clear when there is no overlay), the trace pass, the readback.
// Each leaves the colour image ready for the next, with the barrier that orders them.
#pragma once
#include <cstdint>

#include "gpu_types.h"
#include "vk_frame.h"
#include "vk_pipelines.h"

namespace bvhlab::vk {

struct PassContext {
    const Functions& fn;
    const Pipelines& pipelines;
    VkDescriptorSet set;
    const FrameTargets& targets;
};

/// Clears colour to 0 and depth to 1, draws frame.overlay_range's boxes as 24-vertex line lists
/// (report §3.3.1: a depth range is one first instance and one count).
void record_overlay(const PassContext& pass, VkCommandBuffer cmd, const gpu::FrameParams& frame, float line_width);
/// No overlay: the trace pass reads zero everywhere (no line anywhere).
void record_clear(const PassContext& pass, VkCommandBuffer cmd);
void record_trace(const PassContext& pass, VkCommandBuffer cmd, std::uint32_t traversal);
/// Copies the image into targets.readback, made visible to the host.
void record_readback(const PassContext& pass, VkCommandBuffer cmd);

}  // namespace bvhlab::vk
