// vk_renderer_core.h — what a VulkanRenderer owns, shared with the render jobs it starts (a job
// keeps it alive): the instance and device, the pipelines, the FrameParams buffer and descriptor
// set, the overlay targets, the trace slots and the scene uploaded last. One mutex serialises
// every use: Vulkan queues and command pools are not thread-safe, and the driver crashed when two
// threads rendered at once (issue 8).
#pragma once
#include <memory>
#include <optional>

#include "bvhlab/owned_mutex.h"
#include "bvhlab/vulkan_renderer.h"
#include "vk_commands.h"
#include "vk_device.h"
#include "vk_frame.h"
#include "vk_instance.h"
#include "vk_passes.h"
#include "vk_pipelines.h"
#include "vk_scene.h"

namespace bvhlab::vk {

struct RendererCore {
    explicit RendererCore(const VulkanOptions& options);
    // Every submission is waited for, but an exception may leave one in flight.
    ~RendererCore() { (void)fn.vkDeviceWaitIdle(device.handle()); }

    /// Overlay targets of this size, bound to the descriptor set.
    void ensure_targets(std::uint32_t width, std::uint32_t height);
    /// The widest line the device draws in whole pixels: 1 without wideLines.
    float max_line_width() const;
    /// settings.line_width in whole pixels (whole_line_width) where the device draws wide lines, at most
    /// its widest; else 1 (the only width allowed).
    float line_width(const RenderSettings& settings) const;
    /// A stamp no slot holds yet (trace.comp); after 2^32 - 1 of them the slots are cleared.
    std::uint32_t next_stamp();
    PassContext pass() const { return {fn, pipelines, bindings.set(), *targets}; }

    /// Held by every public operation of the renderer and its jobs; a job's progress callback
    /// calling back into the renderer gets ReentrantCall instead of a deadlock.
    OwnedMutex mutex{"the Vulkan renderer", LockRank::Renderer};
    // Declared in creation order: destroyed in reverse.
    const bool force_staging;
    Functions fn;
    ValidationLog log;
    Instance instance;
    Device device;
    CommandRunner runner;
    Pipelines pipelines;
    FrameBindings bindings;
    TraceSlots slots;
    std::shared_ptr<const SceneBuffers> scene;  ///< the last upload; jobs keep theirs
    std::optional<FrameTargets> targets;
    /// Where a frame's sums come back to the host when they are not host-visible themselves
    /// (a discrete GPU's memory): kept and grown, not allocated for every frame (vk_trace_job.cpp).
    std::optional<Buffer> readback;
    std::uint32_t stamp = 0;
    /// Jobs started on this core, and the number of the one whose overlay (or clear) the targets
    /// hold whole (0: none): a job's later runs do not draw it again.
    std::uint64_t jobs = 0, overlay_job = 0;
};

/// A render job on `scene` (vk_trace_job.cpp); takes `core->mutex` itself.
std::unique_ptr<RenderJob> start_vulkan_job(std::shared_ptr<RendererCore> core,
                                            std::shared_ptr<const SceneBuffers> scene, const RenderSettings& settings);

}  // namespace bvhlab::vk
