// Memory types chosen by use, buffers and images with their own allocation.
#include "vk_memory.h"

#include <cstring>
#include <stdexcept>
#include <string>

#include "vk_check.h"

namespace bvhlab::vk {
namespace {

struct MemoryFlags {
    VkMemoryPropertyFlags required, preferred;
};

MemoryFlags flags_for(MemoryUse use) {
    constexpr VkMemoryPropertyFlags local = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
    constexpr VkMemoryPropertyFlags host = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    switch (use) {
        // The first device-local type: drivers list plain VRAM before the small host-visible BAR
        // window, so large scenes do not land there; where the first is host-visible anyway
        // (lavapipe, integrated GPUs) the upload writes it directly.
        case MemoryUse::DeviceLocal:
            return {local, 0};
        case MemoryUse::Staging:
            return {host, 0};
        case MemoryUse::Readback:
            return {VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT, VK_MEMORY_PROPERTY_HOST_CACHED_BIT};
        case MemoryUse::PerFrame:
            return {host, local};
    }
    return {local, 0};
}

/// The first memory type allowed by `type_bits` with the required and preferred properties, else
/// the first with the required ones.
std::uint32_t find_memory_type(const VkPhysicalDeviceMemoryProperties& memory, std::uint32_t type_bits,
                               MemoryFlags flags) {
    for (VkMemoryPropertyFlags wanted : {flags.required | flags.preferred, flags.required})
        for (std::uint32_t i = 0; i < memory.memoryTypeCount; ++i)
            if ((type_bits & (1u << i)) && (memory.memoryTypes[i].propertyFlags & wanted) == wanted) return i;
    throw std::runtime_error("no Vulkan memory type has properties " + std::to_string(flags.required));
}

}  // namespace

Memory::Memory(const Device& device, const VkMemoryRequirements& needs, MemoryUse use, bool device_address)
    : device_(&device) {
    const PhysicalDevice& physical = device.physical();
    if (physical.max_allocation && needs.size > physical.max_allocation)
        throw std::runtime_error("a Vulkan allocation of " + std::to_string(needs.size) +
                                 " bytes exceeds the device's limit of " + std::to_string(physical.max_allocation) +
                                 " (maxMemoryAllocationSize)");
    const std::uint32_t type = find_memory_type(physical.memory, needs.memoryTypeBits, flags_for(use));
    const VkMemoryPropertyFlags properties = physical.memory.memoryTypes[type].propertyFlags;
    VkMemoryAllocateFlagsInfo address_flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
    address_flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkMemoryAllocateInfo info{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, device_address ? &address_flags : nullptr};
    info.allocationSize = needs.size;
    info.memoryTypeIndex = type;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VK_CHECK(device.fn().vkAllocateMemory(device.handle(), &info, nullptr, &memory));
    memory_ = OwnedMemory(device, memory);
    coherent_ = properties & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    if (properties & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT) {
        void* p = nullptr;
        VK_CHECK(device.fn().vkMapMemory(device.handle(), memory, 0, VK_WHOLE_SIZE, 0, &p));
        mapped_ = static_cast<std::byte*>(p);
    }
}

void Memory::flush() const {
    if (coherent_ || !mapped_) return;
    VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE, nullptr, memory_.get(), 0, VK_WHOLE_SIZE};
    VK_CHECK(device_->fn().vkFlushMappedMemoryRanges(device_->handle(), 1, &range));
}

void Memory::invalidate() const {
    if (coherent_ || !mapped_) return;
    VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE, nullptr, memory_.get(), 0, VK_WHOLE_SIZE};
    VK_CHECK(device_->fn().vkInvalidateMappedMemoryRanges(device_->handle(), 1, &range));
}

Buffer::Buffer(const Device& device, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUse use) : size_(size) {
    const Functions& fn = device.fn();
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = size;
    info.usage = usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    VkBuffer buffer = VK_NULL_HANDLE;
    VK_CHECK(fn.vkCreateBuffer(device.handle(), &info, nullptr, &buffer));
    buffer_ = OwnedBuffer(device, buffer);
    VkMemoryRequirements needs{};
    fn.vkGetBufferMemoryRequirements(device.handle(), buffer, &needs);
    const bool device_address = usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
    memory_ = Memory(device, needs, use, device_address);
    VK_CHECK(fn.vkBindBufferMemory(device.handle(), buffer, memory_.handle(), 0));
    if (device_address) {
        VkBufferDeviceAddressInfo address{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO, nullptr, buffer};
        address_ = fn.vkGetBufferDeviceAddress(device.handle(), &address);
    }
}

void Buffer::write(const void* data, std::size_t bytes, std::size_t offset) {
    if (!host_visible() || offset + bytes > size_)
        throw std::logic_error("Buffer::write outside a host-visible buffer");
    std::memcpy(memory_.mapped() + offset, data, bytes);
    memory_.flush();
}

void Buffer::read(void* out, std::size_t bytes) const { std::memcpy(out, host_bytes(bytes), bytes); }

const std::byte* Buffer::host_bytes(std::size_t bytes, std::size_t offset) const {
    if (!host_visible() || offset > size_ || bytes > size_ - offset)
        throw std::logic_error("a host read outside a host-visible buffer");
    memory_.invalidate();
    return memory_.mapped() + offset;
}

Image::Image(const Device& device, VkExtent2D extent, VkFormat format, VkImageUsageFlags usage,
             VkImageAspectFlags aspect)
    : extent_(extent) {
    const Functions& fn = device.fn();
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = format;
    info.extent = {extent.width, extent.height, 1};
    info.mipLevels = info.arrayLayers = 1;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = usage;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    VkImage image = VK_NULL_HANDLE;
    VK_CHECK(fn.vkCreateImage(device.handle(), &info, nullptr, &image));
    image_ = OwnedImage(device, image);
    VkMemoryRequirements needs{};
    fn.vkGetImageMemoryRequirements(device.handle(), image, &needs);
    memory_ = Memory(device, needs, MemoryUse::DeviceLocal, false);
    VK_CHECK(fn.vkBindImageMemory(device.handle(), image, memory_.handle(), 0));
    VkImageViewCreateInfo view{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    view.image = image;
    view.viewType = VK_IMAGE_VIEW_TYPE_2D;
    view.format = format;
    view.subresourceRange = {aspect, 0, 1, 0, 1};
    VkImageView handle = VK_NULL_HANDLE;
    VK_CHECK(fn.vkCreateImageView(device.handle(), &view, nullptr, &handle));
    view_ = OwnedImageView(device, handle);
}

}  // namespace bvhlab::vk
