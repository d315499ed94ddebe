// vk_physical_device.h — which device renders: the one asked for (VulkanOptions::device or
// BVHLAB_VULKAN_DEVICE), else the first usable discrete GPU, integrated, virtual, then CPU driver.
#pragma once
#include <cstdint>
#include <string>

#include "vk_functions.h"

namespace bvhlab::vk {

struct PhysicalDevice {
    VkPhysicalDevice handle = VK_NULL_HANDLE;
    VkPhysicalDeviceProperties properties{};
    VkPhysicalDeviceMemoryProperties memory{};
    std::uint32_t queue_family = 0;  ///< graphics + compute (+ transfer, implied)
    bool wide_lines = false;         ///< line widths other than 1 (the overlay's line_width)
    /// VK_EXT_line_rasterization's Bresenham lines: the overlay's pixels are then the CPU
    /// reference's (overlay_cpu.cpp steps one pixel per column or row); without it, the default
    /// rule (rectangles where strictLines) covers a second pixel on some steps of a sloped line.
    bool bresenham_lines = false;
    const char* line_extension = nullptr;  ///< the name the device lists it by (EXT, or KHR from Vulkan 1.4)
    VkDeviceSize max_allocation = 0;       ///< maxMemoryAllocationSize

    std::string name() const { return properties.deviceName; }
    std::string type_name() const;  ///< "discrete", "integrated", "virtual", "cpu" or "other"
};

/// `spec`: an index into the enumeration or a substring of the device name (case-insensitive);
/// empty: BVHLAB_VULKAN_DEVICE, else by type. Throws VulkanUnavailable listing the devices when
/// none matches, or naming what the chosen device lacks.
PhysicalDevice select_physical_device(const Functions& fn, VkInstance instance, std::string spec);

}  // namespace bvhlab::vk
