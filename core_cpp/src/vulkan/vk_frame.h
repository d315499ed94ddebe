// vk_frame.h — what a frame renders into and reads: the overlay pass's size-dependent targets
// (recreated only when the size changes), the FrameParams buffer with the one descriptor set both
// pipelines use, the slots in which suspended traces wait between dispatches, and the pixel sums
// of a render.
#pragma once
#include <cstdint>

#include "gpu_types.h"
#include "vk_memory.h"

namespace bvhlab::vk {

/// The overlay pass's colour (lines: rgb + camera distance, report §3.3) and depth images.
struct FrameTargets {
    FrameTargets(const Device& device, std::uint32_t width, std::uint32_t height);

    std::uint32_t width, height;
    Image color;  ///< rgba32f: drawn by the overlay pass, read by the trace pass (storage image)
    Image depth;  ///< D32, the overlay's depth test
};

class FrameBindings {
public:
    FrameBindings(const Device& device, VkDescriptorSetLayout layout);

    void write_params(const gpu::FrameParams& frame);  ///< only while no frame is in flight
    void bind_overlay(VkImageView color);              ///< after the targets change
    VkDescriptorSet set() const { return set_; }

private:
    const Device& device_;
    /// FrameParams, a storage buffer rather than a uniform one: Mesa 22.3's lavapipe recompiles,
    /// and leaks, every shader whose branches read uniform-buffer values, at every submission.
    Buffer params_;
    OwnedDescriptorPool pool_;
    VkDescriptorSet set_ = VK_NULL_HANDLE;  // freed with the pool
};

/// Where suspended traces wait between dispatches (trace.comp, state.glsl): per slot, the state
/// words, the ray stack and the traversal stack; and the counters of slots with work left and of
/// traces that failed.
class TraceSlots {
public:
    explicit TraceSlots(const Device& device);

    /// Room for `slots` slots of these stack sizes (grows, never shrinks); true when the memory
    /// was made anew: the caller then fills state() with zeros (no stamp is 0, so no slot is
    /// taken for a suspended trace).
    bool reserve(std::uint32_t slots, std::uint32_t ray_entries, std::uint32_t node_entries);
    /// Fills the addresses of FrameParams::addr that point here.
    void address(gpu::FrameParams& frame) const;
    void reset_counters();
    std::uint32_t unfinished() const;
    std::uint32_t failed() const;
    const Buffer& state() const { return state_; }

private:
    const Device& device_;
    Buffer state_, rays_, nodes_, counters_;
    std::uint32_t slots_ = 0, ray_entries_ = 0, node_entries_ = 0;
};

/// A render's running sums per pixel (pixel_sums.h): colour + box tests, depth, sample count, the
/// traversal counters where `counters` and the covered samples where `covered_samples` (no buffer
/// otherwise: FrameParams::count_covered).
struct SumBuffers {
    SumBuffers(const Device& device, std::size_t pixels, bool counters, bool covered_samples);
    void address(gpu::FrameParams& frame) const;

    std::size_t pixels;
    Buffer color, depth, samples, counts, covered;
};

}  // namespace bvhlab::vk
