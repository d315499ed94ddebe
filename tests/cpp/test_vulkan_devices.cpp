// Vulkan devices: the renderer reports the device the loader lists, a device is chosen by name,
// index or BVHLAB_VULKAN_DEVICE, and a bad choice or a missing driver is a clear error
// (VulkanUnavailable, which Python turns into a fall-back to the CPU).
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <vulkan/vulkan.h>

#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <string>
#include <vector>

#include "vulkan_fixture.h"

using namespace bvhlab;

namespace {

using namespace test;

/// What the Vulkan loader itself says of each device (its own instance, not the renderer's code).
struct LoaderDevice {
    std::string name, type;
    std::uint32_t max_image_dimension_2d;
};

std::vector<LoaderDevice> loader_devices() {
    std::vector<LoaderDevice> found;
    void* library = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
    if (!library) return found;
    auto get = reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(library, "vkGetInstanceProcAddr"));
    auto create = reinterpret_cast<PFN_vkCreateInstance>(get(nullptr, "vkCreateInstance"));
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.apiVersion = VK_API_VERSION_1_3;
    VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    info.pApplicationInfo = &app;
    VkInstance instance = VK_NULL_HANDLE;
    if (create(&info, nullptr, &instance) == VK_SUCCESS) {
        auto enumerate = reinterpret_cast<PFN_vkEnumeratePhysicalDevices>(get(instance, "vkEnumeratePhysicalDevices"));
        auto properties =
            reinterpret_cast<PFN_vkGetPhysicalDeviceProperties>(get(instance, "vkGetPhysicalDeviceProperties"));
        std::uint32_t count = 0;
        enumerate(instance, &count, nullptr);
        std::vector<VkPhysicalDevice> devices(count);
        enumerate(instance, &count, devices.data());
        for (VkPhysicalDevice d : devices) {
            VkPhysicalDeviceProperties p;
            properties(d, &p);
            const char* type = p.deviceType == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU     ? "discrete"
                               : p.deviceType == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU ? "integrated"
                               : p.deviceType == VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU    ? "virtual"
                               : p.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU            ? "cpu"
                                                                                        : "other";
            found.push_back({p.deviceName, type, p.limits.maxImageDimension2D});
        }
        reinterpret_cast<PFN_vkDestroyInstance>(get(instance, "vkDestroyInstance"))(instance, nullptr);
    }
    dlclose(library);
    return found;
}

}  // namespace

TEST_F(Vulkan, ReportsTheDeviceUsed) {
    // The name, type and image limit are those the loader reports for one of its devices; here
    // with lavapipe alone (the tests' VK_DRIVER_FILES) that device is llvmpipe, a CPU device.
    auto devices = loader_devices();
    ASSERT_FALSE(devices.empty()) << "the loader lists no device";
    bool listed = false;
    for (const LoaderDevice& d : devices) {
        if (d.name != renderer().device_name()) continue;
        listed = true;
        EXPECT_EQ(renderer().device_type(), d.type);
        EXPECT_EQ(renderer().max_image_dimension(), d.max_image_dimension_2d);
    }
    EXPECT_TRUE(listed) << renderer().device_name() << " is not a device the loader lists";
    const char* drivers = std::getenv("VK_DRIVER_FILES");
    if (drivers && std::string(drivers).find("lvp_icd") != std::string::npos) {
        EXPECT_NE(renderer().device_name().find("llvmpipe"), std::string::npos) << renderer().device_name();
        EXPECT_EQ(renderer().device_type(), "cpu");
    }
    std::printf("device: %s (%s)\n", renderer().device_name().c_str(), renderer().device_type().c_str());
}

class VulkanDevice : public ::testing::Test {
protected:
    void SetUp() override {
        test::prepare_vulkan_environment();
        ASSERT_TRUE(vulkan_loader_available()) << "no Vulkan loader: install libvulkan1 and mesa-vulkan-drivers";
    }
    /// Expects VulkanUnavailable whose message contains every one of `needles`.
    static void expect_unavailable(const VulkanOptions& options, std::initializer_list<const char*> needles) {
        try {
            VulkanRenderer r(options);
            ADD_FAILURE() << "no exception; got device " << r.device_name();
        } catch (const VulkanUnavailable& e) {
            for (const char* needle : needles)
                EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
    }
};

TEST_F(VulkanDevice, SelectedByNameSubstringIgnoringCase) {
    VulkanRenderer r(validated({.device = "LLVMpipe"}));
    EXPECT_NE(r.device_name().find("llvmpipe"), std::string::npos);
    EXPECT_EQ(r.device_type(), "cpu");
    expect_no_validation_errors(r);
}

TEST_F(VulkanDevice, SelectedByIndex) {
    VulkanRenderer r(validated({.device = "0"}));
    EXPECT_FALSE(r.device_name().empty());
    expect_no_validation_errors(r);
}

TEST_F(VulkanDevice, IndexOutOfRangeIsAClearError) {
    expect_unavailable(validated({.device = "99"}), {"index 99 is out of range", "0: llvmpipe"});
}

TEST_F(VulkanDevice, UnknownNameIsAClearError) {
    expect_unavailable(validated({.device = "no-such-gpu"}),
                       {"no Vulkan device name contains 'no-such-gpu'", "llvmpipe"});
}

TEST_F(VulkanDevice, EnvironmentVariableChoosesWhenOptionsDoNot) {
    setenv("BVHLAB_VULKAN_DEVICE", "7", 1);
    expect_unavailable(validated(), {"index 7 is out of range"});
    unsetenv("BVHLAB_VULKAN_DEVICE");
}

TEST_F(VulkanDevice, NoDriverIsAClearError) {
    const char* chosen = std::getenv("VK_DRIVER_FILES");
    const std::string drivers = chosen ? chosen : "";
    setenv("VK_DRIVER_FILES", "/nonexistent/icd.json", 1);  // the loader then finds no driver
    expect_unavailable(VulkanOptions{}, {"no Vulkan 1.3 driver found", "mesa-vulkan-drivers"});
    if (chosen) setenv("VK_DRIVER_FILES", drivers.c_str(), 1);
    else unsetenv("VK_DRIVER_FILES");
}

// Where there is no Vulkan driver (here: the loader pointed at a driver file that does not
// exist), constructing a renderer says what to install; Python then falls back to the CPU.
TEST(VulkanUnavailable, ConstructorSaysWhatToInstall) {
    const char* old = std::getenv("VK_DRIVER_FILES");
    std::string saved = old ? old : "";
    setenv("VK_DRIVER_FILES", "/nonexistent/bvhlab_no_driver.json", 1);
    try {
        VulkanRenderer r;
        ADD_FAILURE() << "no exception";
    } catch (const VulkanUnavailable& e) {
        EXPECT_NE(std::string(e.what()).find("install"), std::string::npos) << e.what();
    }
    if (old) setenv("VK_DRIVER_FILES", saved.c_str(), 1);
    else unsetenv("VK_DRIVER_FILES");
}
