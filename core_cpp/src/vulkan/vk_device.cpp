// The logical device: one queue from the graphics + compute family, the features the shaders need.
#include "vk_device.h"

#include "vk_check.h"

namespace bvhlab::vk {

Device::Device(Functions& fn, const PhysicalDevice& physical) : fn_(fn), physical_(physical) {
    const float priority = 1.0f;
    VkDeviceQueueCreateInfo queue{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queue.queueFamilyIndex = physical.queue_family;
    queue.queueCount = 1;
    queue.pQueuePriorities = &priority;
    // select_physical_device checked that these are supported.
    VkPhysicalDeviceLineRasterizationFeaturesEXT lines{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_LINE_RASTERIZATION_FEATURES_EXT};
    lines.bresenhamLines = VK_TRUE;  // where offered (PhysicalDevice::bresenham_lines): the overlay's rule
    VkPhysicalDeviceVulkan13Features v13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES,
                                         physical.bresenham_lines ? &lines : nullptr};
    v13.dynamicRendering = VK_TRUE;
    v13.synchronization2 = VK_TRUE;
    v13.maintenance4 = VK_TRUE;
    VkPhysicalDeviceVulkan12Features v12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &v13};
    v12.bufferDeviceAddress = VK_TRUE;
    VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &v12};
    features.features.wideLines = physical.wide_lines;
    VkDeviceCreateInfo info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &features};
    info.queueCreateInfoCount = 1;
    info.pQueueCreateInfos = &queue;
    if (physical.bresenham_lines)
        info.enabledExtensionCount = 1, info.ppEnabledExtensionNames = &physical.line_extension;
    VK_CHECK(fn.vkCreateDevice(physical.handle, &info, nullptr, &device_));
    try {
        fn.load_device(device_);
    } catch (...) {
        // vkDestroyDevice itself may be what is missing: fetch it alone to clean up
        auto destroy = reinterpret_cast<PFN_vkDestroyDevice>(fn.vkGetDeviceProcAddr(device_, "vkDestroyDevice"));
        if (destroy) destroy(device_, nullptr);
        throw;
    }
    fn.vkGetDeviceQueue(device_, physical.queue_family, 0, &queue_);
}

Device::~Device() {
    // Nothing may still run when the device goes; a failure here cannot be reported from a destructor.
    (void)fn_.vkDeviceWaitIdle(device_);
    fn_.vkDestroyDevice(device_, nullptr);
}

}  // namespace bvhlab::vk
