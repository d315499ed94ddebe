// vk_instance.h — the Vulkan instance, with the Khronos validation layer and a debug messenger
// collecting its warnings and errors when asked for.
#pragma once
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "vk_functions.h"

namespace bvhlab::vk {

/// Validation-layer messages (warnings and errors), filled from the messenger's callback.
class ValidationLog {
public:
    void add(bool is_error, std::string text);
    std::vector<std::string> take();
    std::uint32_t error_count() const;

private:
    mutable std::mutex mutex_;
    std::vector<std::string> messages_;
    std::uint32_t errors_ = 0;
};

class Instance {
public:
    /// Opens the loader, creates a Vulkan 1.3 instance and loads the instance-level functions into
    /// `fn`. With `validation`, enables VK_LAYER_KHRONOS_validation and feeds `log` (which must
    /// outlive the instance). Throws VulkanUnavailable naming what to install.
    Instance(Functions& fn, bool validation, ValidationLog& log);
    ~Instance();
    Instance(const Instance&) = delete;
    Instance& operator=(const Instance&) = delete;

    VkInstance handle() const { return instance_; }

private:
    void create_messenger(ValidationLog& log);

    Functions& fn_;
    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
};

}  // namespace bvhlab::vk
