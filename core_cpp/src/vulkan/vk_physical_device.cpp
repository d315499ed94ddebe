// Device selection: by index or name, else by type; each candidate checked for what bvhlab needs.
#include "vk_physical_device.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "bvhlab/vulkan_renderer.h"
#include "vk_check.h"

namespace bvhlab::vk {
namespace {

std::string type_name(VkPhysicalDeviceType type) {
    switch (type) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
            return "discrete";
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
            return "integrated";
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
            return "virtual";
        case VK_PHYSICAL_DEVICE_TYPE_CPU:
            return "cpu";
        default:
            return "other";
    }
}

/// The documented preference: discrete, integrated, virtual, CPU, anything else.
int type_rank(VkPhysicalDeviceType type) {
    switch (type) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
            return 0;
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
            return 1;
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
            return 2;
        case VK_PHYSICAL_DEVICE_TYPE_CPU:
            return 3;
        default:
            return 4;
    }
}

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

std::vector<PhysicalDevice> enumerate(const Functions& fn, VkInstance instance) {
    std::uint32_t count = 0;
    VK_CHECK(fn.vkEnumeratePhysicalDevices(instance, &count, nullptr));
    std::vector<VkPhysicalDevice> handles(count);
    VK_CHECK(fn.vkEnumeratePhysicalDevices(instance, &count, handles.data()));
    if (handles.empty())
        throw VulkanUnavailable("no Vulkan device found: install a driver, e.g. mesa-vulkan-drivers (lavapipe)");
    std::vector<PhysicalDevice> devices(handles.size());
    for (std::size_t i = 0; i < handles.size(); ++i) {
        devices[i].handle = handles[i];
        fn.vkGetPhysicalDeviceProperties(handles[i], &devices[i].properties);
    }
    return devices;
}

std::string list(const std::vector<PhysicalDevice>& devices) {
    std::string s;
    for (std::size_t i = 0; i < devices.size(); ++i)
        s += (i ? "; " : "") + std::to_string(i) + ": " + devices[i].name() + " (" + devices[i].type_name() + ")";
    return s;
}

/// Queue family with graphics (the overlay pass) and compute (the trace pass), or -1.
int find_queue_family(const Functions& fn, VkPhysicalDevice device) {
    std::uint32_t count = 0;
    fn.vkGetPhysicalDeviceQueueFamilyProperties(device, &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    fn.vkGetPhysicalDeviceQueueFamilyProperties(device, &count, families.data());
    const VkQueueFlags needed = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
    for (std::uint32_t i = 0; i < count; ++i)
        if ((families[i].queueFlags & needed) == needed && families[i].queueCount > 0) return int(i);
    return -1;
}

/// Whether the device offers the extension `name`.
bool has_extension(const Functions& fn, VkPhysicalDevice device, const char* name) {
    std::uint32_t count = 0;
    if (fn.vkEnumerateDeviceExtensionProperties(device, nullptr, &count, nullptr) != VK_SUCCESS) return false;
    std::vector<VkExtensionProperties> extensions(count);
    if (fn.vkEnumerateDeviceExtensionProperties(device, nullptr, &count, extensions.data()) != VK_SUCCESS) return false;
    for (const VkExtensionProperties& e : extensions)
        if (std::strcmp(e.extensionName, name) == 0) return true;
    return false;
}

/// The features the shaders and the passes use: buffer device addresses (the SPIR-V declares
/// PhysicalStorageBufferAddresses: the scene is read through them, so no binding limit caps it),
/// dynamic rendering (the overlay pass), synchronization2 (every barrier and submit), and
/// maintenance4: SPIR-V 1.6 (glslc --target-env=vulkan1.3) declares the workgroup size with
/// LocalSizeId, which needs it.
std::string missing_feature(const Functions& fn, PhysicalDevice& d) {
    VkPhysicalDeviceLineRasterizationFeaturesEXT lines{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_LINE_RASTERIZATION_FEATURES_EXT};
    // the KHR promotion (Vulkan 1.4) has the same structures and values; a driver may list only it
    const char* line_extension = nullptr;
    for (const char* name : {VK_EXT_LINE_RASTERIZATION_EXTENSION_NAME, "VK_KHR_line_rasterization"})
        if (!line_extension && has_extension(fn, d.handle, name)) line_extension = name;
    VkPhysicalDeviceVulkan13Features v13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES,
                                         line_extension ? &lines : nullptr};
    VkPhysicalDeviceVulkan12Features v12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &v13};
    VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &v12};
    fn.vkGetPhysicalDeviceFeatures2(d.handle, &features);
    d.wide_lines = features.features.wideLines;
    d.bresenham_lines = line_extension && lines.bresenhamLines;  // optional: the overlay's pixel rule
    d.line_extension = d.bresenham_lines ? line_extension : nullptr;
    if (!v12.bufferDeviceAddress) return "feature bufferDeviceAddress";
    if (!v13.dynamicRendering) return "feature dynamicRendering";
    if (!v13.synchronization2) return "feature synchronization2";
    if (!v13.maintenance4) return "feature maintenance4";
    return {};
}

/// The overlay draws into, and the trace pass stores to, one rgba32f image; depth is D32.
std::string missing_format(const Functions& fn, VkPhysicalDevice device) {
    VkFormatProperties color{}, depth{};
    fn.vkGetPhysicalDeviceFormatProperties(device, VK_FORMAT_R32G32B32A32_SFLOAT, &color);
    fn.vkGetPhysicalDeviceFormatProperties(device, VK_FORMAT_D32_SFLOAT, &depth);
    const VkFormatFeatureFlags color_needed = VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT |
                                              VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT |
                                              VK_FORMAT_FEATURE_TRANSFER_SRC_BIT | VK_FORMAT_FEATURE_TRANSFER_DST_BIT;
    if ((color.optimalTilingFeatures & color_needed) != color_needed)
        return "R32G32B32A32_SFLOAT as storage image, colour attachment and transfer source/destination";
    if (!(depth.optimalTilingFeatures & VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT))
        return "D32_SFLOAT depth attachment";
    return {};
}

/// Fills the rest of `d`; returns what it lacks (empty: usable).
std::string check_device(const Functions& fn, PhysicalDevice& d) {
    const std::uint32_t api = d.properties.apiVersion;
    if (api < VK_API_VERSION_1_3)
        return "Vulkan 1.3 (it supports " + std::to_string(VK_API_VERSION_MAJOR(api)) + "." +
               std::to_string(VK_API_VERSION_MINOR(api)) + ")";
    int family = find_queue_family(fn, d.handle);
    if (family < 0) return "a queue family with graphics and compute";
    d.queue_family = std::uint32_t(family);
    std::string missing = missing_feature(fn, d);
    if (missing.empty()) missing = missing_format(fn, d.handle);
    VkPhysicalDeviceVulkan11Properties v11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_PROPERTIES};
    VkPhysicalDeviceProperties2 properties{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &v11};
    fn.vkGetPhysicalDeviceProperties2(d.handle, &properties);
    d.max_allocation = v11.maxMemoryAllocationSize;
    // trace.comp keeps its step count in step across the SIMD vector with subgroupMax (shade.glsl)
    if (missing.empty() && (!(v11.subgroupSupportedStages & VK_SHADER_STAGE_COMPUTE_BIT) ||
                            !(v11.subgroupSupportedOperations & VK_SUBGROUP_FEATURE_ARITHMETIC_BIT)))
        missing = "subgroup arithmetic in compute shaders";
    fn.vkGetPhysicalDeviceMemoryProperties(d.handle, &d.memory);
    return missing;
}

/// Index of the device `spec` names (an index or a name substring).
std::size_t find_named(const std::vector<PhysicalDevice>& devices, const std::string& spec) {
    if (!spec.empty() && std::all_of(spec.begin(), spec.end(), [](unsigned char c) { return std::isdigit(c); })) {
        // from_chars, not stoul: no locale, and no libc call (glibc 2.38 renamed strtoul's symbol,
        // which would raise the wheel's glibc requirement to 2.38)
        std::size_t index = devices.size();
        if (spec.size() < 10) std::from_chars(spec.data(), spec.data() + spec.size(), index);
        if (index >= devices.size())
            throw VulkanUnavailable("Vulkan device index " + spec + " is out of range; devices: " + list(devices));
        return index;
    }
    for (std::size_t i = 0; i < devices.size(); ++i)
        if (lower(devices[i].name()).find(lower(spec)) != std::string::npos) return i;
    throw VulkanUnavailable("no Vulkan device name contains '" + spec + "'; devices: " + list(devices));
}

PhysicalDevice select_named(const Functions& fn, std::vector<PhysicalDevice>& devices, const std::string& spec) {
    PhysicalDevice& d = devices[find_named(devices, spec)];
    std::string missing = check_device(fn, d);
    if (!missing.empty())
        throw VulkanUnavailable("Vulkan device " + d.name() + " cannot run bvhlab: it lacks " + missing);
    return d;
}

PhysicalDevice select_by_type(const Functions& fn, std::vector<PhysicalDevice>& devices) {
    const PhysicalDevice* best = nullptr;
    std::string reasons;
    for (PhysicalDevice& d : devices) {
        std::string missing = check_device(fn, d);
        if (!missing.empty()) reasons += (reasons.empty() ? "" : "; ") + d.name() + " lacks " + missing;
        else if (!best || type_rank(d.properties.deviceType) < type_rank(best->properties.deviceType)) best = &d;
    }
    if (!best) throw VulkanUnavailable("no usable Vulkan device: " + reasons);
    return *best;
}

}  // namespace

std::string PhysicalDevice::type_name() const { return vk::type_name(properties.deviceType); }

PhysicalDevice select_physical_device(const Functions& fn, VkInstance instance, std::string spec) {
    if (spec.empty()) {
        const char* env = std::getenv("BVHLAB_VULKAN_DEVICE");
        spec = env ? env : "";
    }
    std::vector<PhysicalDevice> devices = enumerate(fn, instance);
    return spec.empty() ? select_by_type(fn, devices) : select_named(fn, devices, spec);
}

}  // namespace bvhlab::vk
