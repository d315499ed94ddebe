// vk_device.h — the logical device with the features the shaders need, its one queue, and
// Owned<>, the RAII holder of every device-level handle (destroyed when the holder goes, so members
// declared in creation order are freed in reverse).
#pragma once
#include <utility>

#include "vk_functions.h"
#include "vk_physical_device.h"

namespace bvhlab::vk {

class Device {
public:
    /// Creates the device (bufferDeviceAddress, dynamicRendering, synchronization2, maintenance4,
    /// and wideLines where supported) and loads the device-level functions into `fn`.
    Device(Functions& fn, const PhysicalDevice& physical);
    ~Device();  ///< waits until the device is idle first
    Device(const Device&) = delete;
    Device& operator=(const Device&) = delete;

    const Functions& fn() const { return fn_; }
    VkDevice handle() const { return device_; }
    VkQueue queue() const { return queue_; }
    const PhysicalDevice& physical() const { return physical_; }

private:
    Functions& fn_;
    PhysicalDevice physical_;
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
};

/// A device-level handle destroyed with `Destroy` (a member of Functions, e.g.
/// &Functions::vkDestroyBuffer; vkFreeMemory has the same shape). Movable, not copyable.
template <class Handle, auto Destroy>
class Owned {
public:
    Owned() = default;
    Owned(const Device& device, Handle handle) : device_(&device), handle_(handle) {}
    Owned(Owned&& other) noexcept : device_(other.device_), handle_(std::exchange(other.handle_, Handle{})) {}
    Owned& operator=(Owned&& other) noexcept {
        if (this != &other) {
            reset();
            device_ = other.device_;
            handle_ = std::exchange(other.handle_, Handle{});
        }
        return *this;
    }
    ~Owned() { reset(); }

    Handle get() const { return handle_; }
    void reset() {
        if (handle_ != Handle{}) (device_->fn().*Destroy)(device_->handle(), handle_, nullptr);
        handle_ = Handle{};
    }

private:
    const Device* device_ = nullptr;
    Handle handle_{};
};

using OwnedMemory = Owned<VkDeviceMemory, &Functions::vkFreeMemory>;
using OwnedBuffer = Owned<VkBuffer, &Functions::vkDestroyBuffer>;
using OwnedImage = Owned<VkImage, &Functions::vkDestroyImage>;
using OwnedImageView = Owned<VkImageView, &Functions::vkDestroyImageView>;
using OwnedShaderModule = Owned<VkShaderModule, &Functions::vkDestroyShaderModule>;
using OwnedSetLayout = Owned<VkDescriptorSetLayout, &Functions::vkDestroyDescriptorSetLayout>;
using OwnedPipelineLayout = Owned<VkPipelineLayout, &Functions::vkDestroyPipelineLayout>;
using OwnedPipeline = Owned<VkPipeline, &Functions::vkDestroyPipeline>;
using OwnedDescriptorPool = Owned<VkDescriptorPool, &Functions::vkDestroyDescriptorPool>;
using OwnedCommandPool = Owned<VkCommandPool, &Functions::vkDestroyCommandPool>;
using OwnedFence = Owned<VkFence, &Functions::vkDestroyFence>;

}  // namespace bvhlab::vk
