// VkResult names and the error thrown by VK_CHECK.
#include "vk_check.h"

#include <cstring>
#include <stdexcept>
#include <string>

namespace bvhlab::vk {

std::string result_name(VkResult result) {
    switch (result) {
#define BVHLAB_VK_RESULT(name) \
    case name:                 \
        return #name;
        BVHLAB_VK_RESULT(VK_SUCCESS)
        BVHLAB_VK_RESULT(VK_NOT_READY)
        BVHLAB_VK_RESULT(VK_TIMEOUT)
        BVHLAB_VK_RESULT(VK_INCOMPLETE)
        BVHLAB_VK_RESULT(VK_ERROR_OUT_OF_HOST_MEMORY)
        BVHLAB_VK_RESULT(VK_ERROR_OUT_OF_DEVICE_MEMORY)
        BVHLAB_VK_RESULT(VK_ERROR_INITIALIZATION_FAILED)
        BVHLAB_VK_RESULT(VK_ERROR_DEVICE_LOST)
        BVHLAB_VK_RESULT(VK_ERROR_MEMORY_MAP_FAILED)
        BVHLAB_VK_RESULT(VK_ERROR_LAYER_NOT_PRESENT)
        BVHLAB_VK_RESULT(VK_ERROR_EXTENSION_NOT_PRESENT)
        BVHLAB_VK_RESULT(VK_ERROR_FEATURE_NOT_PRESENT)
        BVHLAB_VK_RESULT(VK_ERROR_INCOMPATIBLE_DRIVER)
        BVHLAB_VK_RESULT(VK_ERROR_TOO_MANY_OBJECTS)
        BVHLAB_VK_RESULT(VK_ERROR_FORMAT_NOT_SUPPORTED)
        BVHLAB_VK_RESULT(VK_ERROR_FRAGMENTED_POOL)
        BVHLAB_VK_RESULT(VK_ERROR_UNKNOWN)
        BVHLAB_VK_RESULT(VK_ERROR_OUT_OF_POOL_MEMORY)
        BVHLAB_VK_RESULT(VK_ERROR_INVALID_EXTERNAL_HANDLE)
        BVHLAB_VK_RESULT(VK_ERROR_FRAGMENTATION)
        BVHLAB_VK_RESULT(VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS)
        BVHLAB_VK_RESULT(VK_PIPELINE_COMPILE_REQUIRED)
        BVHLAB_VK_RESULT(VK_ERROR_VALIDATION_FAILED_EXT)
#undef BVHLAB_VK_RESULT
        default:
            return "VkResult " + std::to_string(int(result));
    }
}

void throw_vk_error(VkResult result, const char* call, const char* file, int line) {
    const char* base = std::strrchr(file, '/');
    std::string message = std::string(call) + " failed with " + result_name(result) + " (" + (base ? base + 1 : file) +
                          ":" + std::to_string(line) + ")";
    // What a user can do about it (issue 39: a 16384² render at 256 samples said only the above).
    if (result == VK_ERROR_OUT_OF_DEVICE_MEMORY || result == VK_ERROR_OUT_OF_HOST_MEMORY)
        message =
            "the Vulkan device ran out of memory: lower the resolution or the samples per pixel, or render "
            "on the CPU (backend \"cpu\") [" +
            message + "]";
    throw std::runtime_error(message);
}

}  // namespace bvhlab::vk
