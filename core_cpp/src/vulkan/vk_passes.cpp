// The commands of a frame and the image layouts/barriers between them (report §3.2, Figure 2).
#include "vk_passes.h"

#include <algorithm>

#include "vk_commands.h"

namespace bvhlab::vk {
namespace {

// The overlay image's states through a run. A run starts by discarding the previous contents,
// after the previous run's trace pass read them, or after the parts an interrupted overlay pass
// drew (Cancelled between parts).
constexpr ImageState kColorDiscarded{
    VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_NONE,
    VK_IMAGE_LAYOUT_UNDEFINED};
constexpr ImageState kColorAttachment{VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                                      VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
// A later part of the overlay loads what the parts before drew (LOAD_OP_LOAD reads the attachment).
constexpr ImageState kColorAttachmentLoaded{
    VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
    VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
constexpr ImageState kColorCleared{VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL};
constexpr ImageState kColorTraced{VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT,
                                  VK_IMAGE_LAYOUT_GENERAL};
// Depth: discarded after the previous frame's depth tests, then tested and written.
constexpr VkPipelineStageFlags2 kDepthStages =
    VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT;
constexpr ImageState kDepthDiscarded{kDepthStages, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                                     VK_IMAGE_LAYOUT_UNDEFINED};
constexpr ImageState kDepthAttachment{
    kDepthStages, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
    VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL};

VkRenderingAttachmentInfo attachment(VkImageView view, VkImageLayout layout, VkAttachmentLoadOp load,
                                     VkAttachmentStoreOp store, VkClearValue clear) {
    VkRenderingAttachmentInfo info{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    info.imageView = view;
    info.imageLayout = layout;
    info.loadOp = load;
    info.storeOp = store;
    info.clearValue = clear;
    return info;
}

void begin_overlay_rendering(const PassContext& pass, VkCommandBuffer cmd, const OverlayPart& part) {
    const FrameTargets& t = pass.targets;
    VkClearValue no_line{}, far_depth{};
    far_depth.depthStencil.depth = 1.0f;
    const VkAttachmentLoadOp load = part.opens ? VK_ATTACHMENT_LOAD_OP_CLEAR : VK_ATTACHMENT_LOAD_OP_LOAD;
    // colour (0,0,0,0): alpha 0 tells the trace pass "no line here" (report §3.3)
    VkRenderingAttachmentInfo color =
        attachment(t.color.view(), kColorAttachment.layout, load, VK_ATTACHMENT_STORE_OP_STORE, no_line);
    VkRenderingAttachmentInfo depth =
        attachment(t.depth.view(), kDepthAttachment.layout, load,
                   part.closes ? VK_ATTACHMENT_STORE_OP_DONT_CARE : VK_ATTACHMENT_STORE_OP_STORE, far_depth);
    VkRenderingInfo info{VK_STRUCTURE_TYPE_RENDERING_INFO};
    info.renderArea = {{0, 0}, {t.width, t.height}};
    info.layerCount = 1;
    info.colorAttachmentCount = 1;
    info.pColorAttachments = &color;
    info.pDepthAttachment = &depth;
    pass.fn.vkCmdBeginRendering(cmd, &info);
}

}  // namespace

void record_overlay(const PassContext& pass, VkCommandBuffer cmd, float line_width, const OverlayPart& part) {
    const Functions& fn = pass.fn;
    const FrameTargets& t = pass.targets;
    // the first part discards what was there; a later one reads what the parts before drew
    image_barrier(fn, cmd, t.color.handle(), VK_IMAGE_ASPECT_COLOR_BIT, part.opens ? kColorDiscarded : kColorAttachment,
                  part.opens ? kColorAttachment : kColorAttachmentLoaded);
    image_barrier(fn, cmd, t.depth.handle(), VK_IMAGE_ASPECT_DEPTH_BIT, part.opens ? kDepthDiscarded : kDepthAttachment,
                  kDepthAttachment);
    begin_overlay_rendering(pass, cmd, part);
    fn.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pass.pipelines.overlay());
    VkDescriptorSet set = pass.set;
    fn.vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pass.pipelines.layout(), 0, 1, &set, 0, nullptr);
    VkViewport viewport{0, 0, float(t.width), float(t.height), 0, 1};
    VkRect2D scissor{{0, 0}, {t.width, t.height}};
    fn.vkCmdSetViewport(cmd, 0, 1, &viewport);
    fn.vkCmdSetScissor(cmd, 0, 1, &scissor);
    fn.vkCmdSetLineWidth(cmd, line_width);
    // overlay.vert reads box gl_InstanceIndex, which starts at firstInstance
    if (part.count) fn.vkCmdDraw(cmd, 24, part.count, 0, part.first);
    fn.vkCmdEndRendering(cmd);
    if (part.closes)
        image_barrier(fn, cmd, t.color.handle(), VK_IMAGE_ASPECT_COLOR_BIT, kColorAttachment, kColorTraced);
}

void record_clear(const PassContext& pass, VkCommandBuffer cmd) {
    const Functions& fn = pass.fn;
    VkImage image = pass.targets.color.handle();
    image_barrier(fn, cmd, image, VK_IMAGE_ASPECT_COLOR_BIT, kColorDiscarded, kColorCleared);
    VkClearColorValue zero{};
    VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    fn.vkCmdClearColorImage(cmd, image, kColorCleared.layout, &zero, 1, &range);
    image_barrier(fn, cmd, image, VK_IMAGE_ASPECT_COLOR_BIT, kColorCleared, kColorTraced);
}

void record_trace_round(const PassContext& pass, VkCommandBuffer cmd, std::uint32_t traversal, std::uint32_t width,
                        std::uint32_t height) {
    const Functions& fn = pass.fn;
    // the previous round's (or the fills') writes to the slots and the sums come first
    memory_barrier(fn, cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_CLEAR_BIT,
                   VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                   VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    fn.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pass.pipelines.trace(traversal));
    VkDescriptorSet set = pass.set;
    fn.vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pass.pipelines.layout(), 0, 1, &set, 0, nullptr);
    // rounded up; trace.comp returns early outside the tile
    fn.vkCmdDispatch(cmd, (width + gpu::TRACE_GROUP_X - 1) / gpu::TRACE_GROUP_X,
                     (height + gpu::TRACE_GROUP_Y - 1) / gpu::TRACE_GROUP_Y, 1);
    memory_barrier(fn, cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
}

void record_fill(const Functions& fn, VkCommandBuffer cmd, const Buffer& buffer, std::uint32_t pattern) {
    // earlier shader reads and writes of the buffer are done before it is overwritten
    memory_barrier(fn, cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                   VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    fn.vkCmdFillBuffer(cmd, buffer.handle(), 0, VK_WHOLE_SIZE, pattern);
    memory_barrier(
        fn, cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
        VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_HOST_BIT,
        VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_HOST_READ_BIT);
}

void record_copies_to_host(const Functions& fn, VkCommandBuffer cmd, const HostCopy* copies, std::size_t count,
                           const Buffer& to) {
    memory_barrier(fn, cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_CLEAR_BIT,
                   VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
                   VK_ACCESS_2_TRANSFER_READ_BIT);
    for (std::size_t k = 0; k < count; ++k) {
        const VkBufferCopy region{0, copies[k].offset, copies[k].bytes};
        fn.vkCmdCopyBuffer(cmd, copies[k].from->handle(), to.handle(), 1, &region);
    }
    memory_barrier(fn, cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                   VK_ACCESS_2_HOST_READ_BIT);
}

}  // namespace bvhlab::vk
