// Uploads into device-local buffers: direct writes or a staging buffer, in chunks.
#include "vk_upload.h"

#include <algorithm>

namespace bvhlab::vk {
namespace {

constexpr std::size_t kMinBufferBytes = 16;
/// The staging buffer is reused chunk by chunk, so an upload never holds a second copy of a large
/// scene in host-visible memory.
constexpr std::size_t kStagingChunkBytes = std::size_t(64) << 20;

void upload_staged(const Device& device, CommandRunner& runner, const Buffer& target, const std::byte* data,
                   std::size_t bytes) {
    const Functions& fn = device.fn();
    const std::size_t chunk = std::min(bytes, kStagingChunkBytes);
    Buffer staging(device, chunk, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUse::Staging);
    for (std::size_t offset = 0; offset < bytes; offset += chunk) {
        const std::size_t n = std::min(chunk, bytes - offset);
        staging.write(data + offset, n);  // the previous copy from it finished: run() waited
        runner.run([&](VkCommandBuffer cmd) {
            VkBufferCopy region{0, offset, n};
            fn.vkCmdCopyBuffer(cmd, staging.handle(), target.handle(), 1, &region);
            // Shaders of later submissions (overlay vertex, trace compute) read what the copy wrote.
            memory_barrier(fn, cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                           VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                           VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
        });
    }
}

}  // namespace

Buffer upload_array(const Device& device, CommandRunner& runner, const void* data, std::size_t bytes,
                    bool force_staging) {
    const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                     VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    Buffer buffer(device, std::max(bytes, kMinBufferBytes), usage, MemoryUse::DeviceLocal);
    if (bytes == 0) return buffer;
    // Host writes before a submission are visible to it (Vulkan spec, "host write ordering").
    if (buffer.host_visible() && !force_staging) buffer.write(data, bytes);
    else upload_staged(device, runner, buffer, static_cast<const std::byte*>(data), bytes);
    return buffer;
}

}  // namespace bvhlab::vk
