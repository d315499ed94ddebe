// vk_passes.h — the commands of a render (report §3.2, Figure 2): the overlay pass (or a clear
// when there is no overlay), rounds of the trace pass over a tile, and the fills and copies around
// them. Each leaves its resources ready for the next, with the barrier that orders them.
#pragma once
#include <cstddef>
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

/// Boxes the overlay pass draws in one submission (its parts, OverlayPart): a flat tree's range
/// of 2M boxes in one draw took 3.8 s on lavapipe, and Ctrl-C waited for it (probe).
inline constexpr std::uint32_t kOverlayBoxesPerPart = 1u << 16;

/// Which of the overlay pass's boxes one submission draws: [first, first + count); the first part
/// clears colour to 0 and depth to 1, the others keep what the parts before drew (depth too, so
/// the nearest line wins across parts as within one), the last leaves the colour image for the
/// trace pass to read.
struct OverlayPart {
    std::uint32_t first, count;
    bool opens, closes;
};

/// Draws one part of the boxes [overlay_first_box, overlay_last_box) as 24-vertex line lists
/// (report §3.3.1: a depth range is one first instance and one count).
void record_overlay(const PassContext& pass, VkCommandBuffer cmd, float line_width, const OverlayPart& part);
/// No overlay: the trace pass reads zero everywhere (no line anywhere).
void record_clear(const PassContext& pass, VkCommandBuffer cmd);
/// One dispatch of trace.comp over a tile of width × height pixels, ordered after every earlier
/// transfer and compute write, and made visible to the host (the counter of unfinished slots).
void record_trace_round(const PassContext& pass, VkCommandBuffer cmd, std::uint32_t traversal, std::uint32_t width,
                        std::uint32_t height);
/// Fills `bytes` of `buffer` with the 32-bit `pattern`, ordered before later compute shaders.
void record_fill(const Functions& fn, VkCommandBuffer cmd, const Buffer& buffer, std::uint32_t pattern);
/// A device buffer's first `bytes` copied to `offset` in a host-visible buffer.
struct HostCopy {
    const Buffer* from;
    VkDeviceSize bytes, offset;
};
/// The copies, after the compute passes' writes, and visible to the host's reads after the
/// submission's fence. The caller checks that each fits both buffers (a throw here would leave the
/// command buffer recording).
void record_copies_to_host(const Functions& fn, VkCommandBuffer cmd, const HostCopy* copies, std::size_t count,
                           const Buffer& to);

}  // namespace bvhlab::vk
