// vk_functions.h — every Vulkan entry point the backend calls, as X-macro lists, and the table that
// holds them. The backend never links against libvulkan (VK_NO_PROTOTYPES): the loader is opened
// at run time (vk_loader.cpp), so the module imports and the CPU backend runs on machines that have
// no Vulkan at all.
#pragma once
#ifndef VK_NO_PROTOTYPES
#define VK_NO_PROTOTYPES
#endif
#include <vulkan/vulkan.h>

namespace bvhlab::vk {

/// Loaded with vkGetInstanceProcAddr(nullptr, ...): usable before an instance exists.
#define BVHLAB_VK_GLOBAL_FUNCTIONS(X)         \
    X(vkEnumerateInstanceVersion)             \
    X(vkEnumerateInstanceLayerProperties)     \
    X(vkEnumerateInstanceExtensionProperties) \
    X(vkCreateInstance)

#define BVHLAB_VK_INSTANCE_FUNCTIONS(X)         \
    X(vkDestroyInstance)                        \
    X(vkEnumeratePhysicalDevices)               \
    X(vkEnumerateDeviceExtensionProperties)     \
    X(vkGetPhysicalDeviceProperties)            \
    X(vkGetPhysicalDeviceProperties2)           \
    X(vkGetPhysicalDeviceFeatures2)             \
    X(vkGetPhysicalDeviceFormatProperties)      \
    X(vkGetPhysicalDeviceMemoryProperties)      \
    X(vkGetPhysicalDeviceQueueFamilyProperties) \
    X(vkCreateDevice)                           \
    X(vkGetDeviceProcAddr)

/// VK_EXT_debug_utils: loaded only when validation is on (the extension is enabled then).
#define BVHLAB_VK_DEBUG_UTILS_FUNCTIONS(X) \
    X(vkCreateDebugUtilsMessengerEXT)      \
    X(vkDestroyDebugUtilsMessengerEXT)

#define BVHLAB_VK_DEVICE_FUNCTIONS(X) \
    X(vkDestroyDevice)                \
    X(vkGetDeviceQueue)               \
    X(vkDeviceWaitIdle)               \
    X(vkAllocateMemory)               \
    X(vkFreeMemory)                   \
    X(vkMapMemory)                    \
    X(vkFlushMappedMemoryRanges)      \
    X(vkInvalidateMappedMemoryRanges) \
    X(vkCreateBuffer)                 \
    X(vkDestroyBuffer)                \
    X(vkGetBufferMemoryRequirements)  \
    X(vkBindBufferMemory)             \
    X(vkGetBufferDeviceAddress)       \
    X(vkCreateImage)                  \
    X(vkDestroyImage)                 \
    X(vkGetImageMemoryRequirements)   \
    X(vkBindImageMemory)              \
    X(vkCreateImageView)              \
    X(vkDestroyImageView)             \
    X(vkCreateShaderModule)           \
    X(vkDestroyShaderModule)          \
    X(vkCreateDescriptorSetLayout)    \
    X(vkDestroyDescriptorSetLayout)   \
    X(vkCreatePipelineLayout)         \
    X(vkDestroyPipelineLayout)        \
    X(vkCreateComputePipelines)       \
    X(vkCreateGraphicsPipelines)      \
    X(vkDestroyPipeline)              \
    X(vkCreateDescriptorPool)         \
    X(vkDestroyDescriptorPool)        \
    X(vkAllocateDescriptorSets)       \
    X(vkUpdateDescriptorSets)         \
    X(vkCreateCommandPool)            \
    X(vkDestroyCommandPool)           \
    X(vkAllocateCommandBuffers)       \
    X(vkResetCommandBuffer)           \
    X(vkBeginCommandBuffer)           \
    X(vkEndCommandBuffer)             \
    X(vkCreateFence)                  \
    X(vkDestroyFence)                 \
    X(vkWaitForFences)                \
    X(vkResetFences)                  \
    X(vkQueueSubmit2)                 \
    X(vkCmdPipelineBarrier2)          \
    X(vkCmdBeginRendering)            \
    X(vkCmdEndRendering)              \
    X(vkCmdBindPipeline)              \
    X(vkCmdBindDescriptorSets)        \
    X(vkCmdSetViewport)               \
    X(vkCmdSetScissor)                \
    X(vkCmdSetLineWidth)              \
    X(vkCmdDraw)                      \
    X(vkCmdDispatch)                  \
    X(vkCmdClearColorImage)           \
    X(vkCmdCopyBuffer)                \
    X(vkCmdFillBuffer)

/// The function table: one per renderer, filled level by level as the instance and the device
/// come to exist (vk_loader.cpp).
struct Functions {
#define BVHLAB_VK_MEMBER(name) PFN_##name name = nullptr;
    PFN_vkGetInstanceProcAddr vkGetInstanceProcAddr = nullptr;
    BVHLAB_VK_GLOBAL_FUNCTIONS(BVHLAB_VK_MEMBER)
    BVHLAB_VK_INSTANCE_FUNCTIONS(BVHLAB_VK_MEMBER)
    BVHLAB_VK_DEBUG_UTILS_FUNCTIONS(BVHLAB_VK_MEMBER)
    BVHLAB_VK_DEVICE_FUNCTIONS(BVHLAB_VK_MEMBER)
#undef BVHLAB_VK_MEMBER

    /// Opens the loader; throws VulkanUnavailable naming what to install.
    void load_global();
    void load_instance(VkInstance instance);
    void load_debug_utils(VkInstance instance);
    void load_device(VkDevice device);
};

}  // namespace bvhlab::vk
