// vk_memory.h — buffers and images with their own memory (a handful per renderer, so one
// allocation each), persistently mapped where the memory is host-visible.
#pragma once
#include <cstddef>

#include "vk_device.h"

namespace bvhlab::vk {

/// What a piece of memory is for; decides its memory type (find_memory_type in vk_memory.cpp).
enum class MemoryUse {
    DeviceLocal,  ///< read by shaders; written directly when it happens to be host-visible too (lavapipe)
    Staging,      ///< written by the host, read by transfers
    Readback,     ///< written by transfers, read by the host (cached where possible)
    PerFrame,     ///< rewritten by the host every frame: host-visible, device-local where possible
};

/// One VkDeviceMemory allocation; mapped for its lifetime when host-visible.
class Memory {
public:
    Memory() = default;
    Memory(const Device& device, const VkMemoryRequirements& needs, MemoryUse use, bool device_address);

    VkDeviceMemory handle() const { return memory_.get(); }
    std::byte* mapped() const { return mapped_; }  ///< null unless host-visible
    void flush() const;                            ///< host writes → device, where the memory is not coherent
    void invalidate() const;                       ///< device writes → host, where the memory is not coherent

private:
    const Device* device_ = nullptr;
    OwnedMemory memory_;
    std::byte* mapped_ = nullptr;
    bool coherent_ = true;
};

class Buffer {
public:
    Buffer() = default;
    /// With VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT in `usage`, address() is the buffer's.
    Buffer(const Device& device, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUse use);

    VkBuffer handle() const { return buffer_.get(); }
    VkDeviceSize size() const { return size_; }
    VkDeviceAddress address() const { return address_; }
    bool host_visible() const { return memory_.mapped() != nullptr; }
    /// Host access; only where host_visible().
    void write(const void* data, std::size_t bytes, std::size_t offset = 0);
    void read(void* out, std::size_t bytes) const;
    /// The mapped bytes [offset, offset + bytes), the device's writes made visible, to read in
    /// place; only where host_visible().
    const std::byte* host_bytes(std::size_t bytes, std::size_t offset = 0) const;

private:
    Memory memory_;  // declared first: freed after the buffer
    OwnedBuffer buffer_;
    VkDeviceSize size_ = 0;
    VkDeviceAddress address_ = 0;
};

/// A 2D device-local image with one mip level and a view of the whole of it.
class Image {
public:
    Image() = default;
    Image(const Device& device, VkExtent2D extent, VkFormat format, VkImageUsageFlags usage, VkImageAspectFlags aspect);

    VkImage handle() const { return image_.get(); }
    VkImageView view() const { return view_.get(); }
    VkExtent2D extent() const { return extent_; }

private:
    Memory memory_;
    OwnedImage image_;
    OwnedImageView view_;
    VkExtent2D extent_{};
};

}  // namespace bvhlab::vk
