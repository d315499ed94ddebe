// vk_check.h — every Vulkan call is checked: a failure throws std::runtime_error naming the call,
// the VkResult and the source line.
#pragma once
#include <string>

#include "vk_functions.h"

namespace bvhlab::vk {

/// "VK_ERROR_OUT_OF_DEVICE_MEMORY", ...; the number for codes this list does not know.
std::string result_name(VkResult result);

[[noreturn]] void throw_vk_error(VkResult result, const char* call, const char* file, int line);

inline void check(VkResult result, const char* call, const char* file, int line) {
    if (result != VK_SUCCESS) throw_vk_error(result, call, file, line);
}

}  // namespace bvhlab::vk

#define VK_CHECK(call) ::bvhlab::vk::check((call), #call, __FILE__, __LINE__)
