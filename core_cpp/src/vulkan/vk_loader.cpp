// The Vulkan loader, opened at run time: libvulkan.so.1 and its vkGetInstanceProcAddr, from which
// every other entry point is fetched level by level (instance, then device functions, which skip
// the loader's dispatch trampolines).
#include <dlfcn.h>

#include <string>

#include "bvhlab/vulkan_renderer.h"
#include "vk_functions.h"

namespace bvhlab::vk {
namespace {

constexpr const char* kInstallHint =
    "install the Vulkan loader (Debian/Ubuntu: libvulkan1) and a driver, e.g. mesa-vulkan-drivers "
    "(lavapipe, which runs on the CPU)";

/// vkGetInstanceProcAddr of libvulkan.so.1, or null with the reason in `error`. The library stays
/// loaded for the life of the process, as if linked: drivers it loads may keep pointers into it.
PFN_vkGetInstanceProcAddr open_loader(std::string& error) {
    static std::string failure;
    static PFN_vkGetInstanceProcAddr entry = [] {
        void* library = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
        if (!library) {
            const char* why = dlerror();
            failure = why ? why : "dlopen(libvulkan.so.1) failed";
            return PFN_vkGetInstanceProcAddr(nullptr);
        }
        auto f = reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(library, "vkGetInstanceProcAddr"));
        if (!f) failure = "libvulkan.so.1 has no vkGetInstanceProcAddr";
        return f;
    }();
    error = failure;
    return entry;
}

template <class F>
void require(F* slot, PFN_vkVoidFunction f, const char* name) {
    if (!f) throw VulkanUnavailable(std::string("the Vulkan loader or driver lacks ") + name + ": " + kInstallHint);
    *slot = reinterpret_cast<F>(f);
}

}  // namespace

// Each loader below defines `get` (name -> function pointer) for the macro.
#define BVHLAB_VK_LOAD(name) require(&name, get(#name), #name);

void Functions::load_global() {
    std::string error;
    vkGetInstanceProcAddr = open_loader(error);
    if (!vkGetInstanceProcAddr) throw VulkanUnavailable("Vulkan is not available (" + error + "): " + kInstallHint);
    auto get = [this](const char* name) { return vkGetInstanceProcAddr(nullptr, name); };
    BVHLAB_VK_GLOBAL_FUNCTIONS(BVHLAB_VK_LOAD)
}

void Functions::load_instance(VkInstance instance) {
    auto get = [&](const char* name) { return vkGetInstanceProcAddr(instance, name); };
    BVHLAB_VK_INSTANCE_FUNCTIONS(BVHLAB_VK_LOAD)
}

void Functions::load_debug_utils(VkInstance instance) {
    auto get = [&](const char* name) { return vkGetInstanceProcAddr(instance, name); };
    BVHLAB_VK_DEBUG_UTILS_FUNCTIONS(BVHLAB_VK_LOAD)
}

void Functions::load_device(VkDevice device) {
    auto get = [&](const char* name) { return vkGetDeviceProcAddr(device, name); };
    BVHLAB_VK_DEVICE_FUNCTIONS(BVHLAB_VK_LOAD)
}

#undef BVHLAB_VK_LOAD

}  // namespace bvhlab::vk

namespace bvhlab {

bool vulkan_loader_available() {
    std::string error;
    return vk::open_loader(error) != nullptr;
}

}  // namespace bvhlab
