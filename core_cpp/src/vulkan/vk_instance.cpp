// The instance, the validation layer and its messenger (messages collected for the tests).
#include "vk_instance.h"

#include <algorithm>
#include <cstring>
#include <string>
#include <utility>

#include "bvhlab/vulkan_renderer.h"
#include "vk_check.h"

namespace bvhlab::vk {
namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                          VkDebugUtilsMessageTypeFlagsEXT,
                                          const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    const bool is_error = severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    std::string text = is_error ? "error: " : "warning: ";
    if (data->pMessageIdName) text += std::string("[") + data->pMessageIdName + "] ";
    text += data->pMessage ? data->pMessage : "";
    static_cast<ValidationLog*>(user)->add(is_error, std::move(text));
    return VK_FALSE;  // never abort the call that triggered it
}

VkDebugUtilsMessengerCreateInfoEXT messenger_info(ValidationLog& log) {
    VkDebugUtilsMessengerCreateInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    info.messageSeverity =
        VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    info.pfnUserCallback = on_message;
    info.pUserData = &log;
    return info;
}

bool has_layer(const Functions& fn, const char* name) {
    std::uint32_t count = 0;
    VK_CHECK(fn.vkEnumerateInstanceLayerProperties(&count, nullptr));
    std::vector<VkLayerProperties> layers(count);
    VK_CHECK(fn.vkEnumerateInstanceLayerProperties(&count, layers.data()));
    return std::any_of(layers.begin(), layers.end(),
                       [&](const auto& l) { return std::strcmp(l.layerName, name) == 0; });
}

/// The loader and the validation layer must both be there before we ask for them.
void check_prerequisites(const Functions& fn, bool validation) {
    std::uint32_t version = 0;
    VK_CHECK(fn.vkEnumerateInstanceVersion(&version));
    if (version < VK_API_VERSION_1_3)
        throw VulkanUnavailable("the Vulkan loader supports Vulkan " + std::to_string(VK_API_VERSION_MAJOR(version)) +
                                "." + std::to_string(VK_API_VERSION_MINOR(version)) +
                                "; bvhlab needs 1.3: update libvulkan1");
    if (validation && !has_layer(fn, kValidationLayer))
        throw VulkanUnavailable(std::string("validation was requested but ") + kValidationLayer +
                                " is not installed: install vulkan-validationlayers");
}

}  // namespace

void ValidationLog::add(bool is_error, std::string text) {
    std::lock_guard lock(mutex_);
    messages_.push_back(std::move(text));
    errors_ += is_error ? 1 : 0;
}

std::vector<std::string> ValidationLog::take() {
    std::lock_guard lock(mutex_);
    return std::exchange(messages_, {});
}

std::uint32_t ValidationLog::error_count() const {
    std::lock_guard lock(mutex_);
    return errors_;
}

Instance::Instance(Functions& fn, bool validation, ValidationLog& log) : fn_(fn) {
    fn.load_global();
    check_prerequisites(fn, validation);
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "bvhlab";
    app.apiVersion = VK_API_VERSION_1_3;
    // Chained into the create info, the messenger also reports on vkCreate/DestroyInstance.
    VkDebugUtilsMessengerCreateInfoEXT debug = messenger_info(log);
    const char* layers[] = {kValidationLayer};
    const char* extensions[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME};
    VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    info.pApplicationInfo = &app;
    if (validation) {
        info.pNext = &debug;
        info.enabledLayerCount = info.enabledExtensionCount = 1;
        info.ppEnabledLayerNames = layers;
        info.ppEnabledExtensionNames = extensions;  // the validation layer provides it
    }
    VkResult result = fn.vkCreateInstance(&info, nullptr, &instance_);
    if (result == VK_ERROR_INCOMPATIBLE_DRIVER)
        throw VulkanUnavailable("no Vulkan 1.3 driver found: install one, e.g. mesa-vulkan-drivers (lavapipe)");
    VK_CHECK(result);
    try {
        fn.load_instance(instance_);
        if (validation) create_messenger(log);
    } catch (...) {
        if (fn.vkDestroyInstance) fn.vkDestroyInstance(instance_, nullptr);
        throw;
    }
}

void Instance::create_messenger(ValidationLog& log) {
    fn_.load_debug_utils(instance_);
    VkDebugUtilsMessengerCreateInfoEXT info = messenger_info(log);
    VK_CHECK(fn_.vkCreateDebugUtilsMessengerEXT(instance_, &info, nullptr, &messenger_));
}

Instance::~Instance() {
    if (messenger_) fn_.vkDestroyDebugUtilsMessengerEXT(instance_, messenger_, nullptr);
    fn_.vkDestroyInstance(instance_, nullptr);
}

}  // namespace bvhlab::vk
