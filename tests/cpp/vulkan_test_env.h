// Environment for the Vulkan tests and tools: lavapipe unless a driver was chosen, Mesa's shader
// cache in the build tree, and (under ASan) the driver libraries pinned for LeakSanitizer.
#pragma once
#include <dlfcn.h>

#include <cstdlib>

namespace bvhlab::test {

#if defined(__SANITIZE_ADDRESS__)  // GCC
#define BVHLAB_TEST_ASAN 1
#elif defined(__has_feature)  // clang
#if __has_feature(address_sanitizer)
#define BVHLAB_TEST_ASAN 1
#endif
#endif
#if defined(BVHLAB_TEST_ASAN)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif

/// The Vulkan loader unloads the driver and the layers with the instance; LeakSanitizer reports at
/// exit, when it can no longer name their frames, so tests/cpp/lsan.supp could not match them.
/// Under ASan, keep them loaded (RTLD_NODELETE) so that their leaks carry their library's name.
inline void pin_driver_libraries() {
    if (!kAddressSanitizer) return;
    for (const char* library :
         {"libvulkan_lvp.so", "libVkLayer_khronos_validation.so", "libVkLayer_MESA_device_select.so"})
        dlopen(library, RTLD_NOW | RTLD_NODELETE);  // absent: nothing to pin
}

/// Pins lavapipe (unless the caller chose a driver) and keeps Mesa's shader cache in the build tree.
inline void prepare_vulkan_environment() {
    pin_driver_libraries();
    if (!std::getenv("VK_DRIVER_FILES") && !std::getenv("VK_ICD_FILENAMES"))
        setenv("VK_DRIVER_FILES", "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json", 1);
    setenv("MESA_SHADER_CACHE_DIR", BVHLAB_TEST_CACHE_DIR, 0);
    setenv("XDG_CACHE_HOME", BVHLAB_TEST_CACHE_DIR, 0);
}

}  // namespace bvhlab::test
