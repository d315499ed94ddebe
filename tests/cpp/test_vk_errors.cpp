// What a failed Vulkan call tells the user (vk_check.cpp): the call, the result and the line, and
// for running out of memory what to lower (issue 39: a 16384² render at 256 samples said only
// "vkCreateBuffer(...) failed with VK_ERROR_OUT_OF_DEVICE_MEMORY").
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "vk_check.h"

using namespace bvhlab::vk;

namespace {

std::string message_of(VkResult result) {
    try {
        throw_vk_error(result, "fn.vkCreateBuffer(device, &info, nullptr, &buffer)", "/src/vk_memory.cpp", 92);
    } catch (const std::runtime_error& e) { return e.what(); }
    return "";
}

TEST(VulkanErrors, NameTheCallTheResultAndTheLine) {
    const std::string m = message_of(VK_ERROR_DEVICE_LOST);
    EXPECT_NE(m.find("vkCreateBuffer"), std::string::npos) << m;
    EXPECT_NE(m.find("VK_ERROR_DEVICE_LOST"), std::string::npos) << m;
    EXPECT_NE(m.find("vk_memory.cpp:92"), std::string::npos) << m;
    EXPECT_EQ(m.find("/src/"), std::string::npos) << m;
    EXPECT_EQ(m.find("lower"), std::string::npos) << m;
}

TEST(VulkanErrors, OutOfMemorySaysWhatToLower) {
    for (VkResult result : {VK_ERROR_OUT_OF_DEVICE_MEMORY, VK_ERROR_OUT_OF_HOST_MEMORY}) {
        const std::string m = message_of(result);
        EXPECT_NE(m.find("ran out of memory"), std::string::npos) << m;
        EXPECT_NE(m.find("lower the resolution or the samples"), std::string::npos) << m;
        EXPECT_NE(m.find("\"cpu\""), std::string::npos) << m;
        EXPECT_NE(m.find(result_name(result)), std::string::npos) << m;
    }
}

}  // namespace
