// The Vulkan tests' shared fixture: one validated renderer per test binary (an instance with the
// validation layer takes a while to create), zero validation errors after every test, and images
// against the CPU reference (same FrameParams, same tracer code) within stated tolerances.
#pragma once
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "bvhlab/vulkan_renderer.h"
#include "render_scenes.h"
#include "vulkan_test_env.h"

namespace bvhlab::test {

inline VulkanOptions validated(VulkanOptions options = {}) {
    options.validation = true;
    return options;
}

/// Prints what the validation layer said and fails on any error.
inline void expect_no_validation_errors(VulkanRenderer& r) {
    for (const std::string& m : r.take_validation_messages()) std::printf("[validation] %s\n", m.c_str());
    EXPECT_EQ(r.validation_error_count(), 0u);
}

inline std::vector<float> render_vulkan(VulkanRenderer& r, const RenderSettings& s) {
    std::vector<float> image(std::size_t(s.width) * s.height * 4);
    r.render(s, {image.data()});
    return image;
}

inline std::vector<float> render_reference(const RenderScene& scene, const RenderSettings& s) {
    std::vector<float> image(std::size_t(s.width) * s.height * 4);
    render_cpu(scene, s, {image.data()});
    return image;
}

class Vulkan : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        prepare_vulkan_environment();
        if (vulkan_loader_available()) renderer_ = new VulkanRenderer(validated());
    }
    static void TearDownTestSuite() {
        delete renderer_;
        renderer_ = nullptr;
    }
    void SetUp() override {
        // make test installs lavapipe: a missing loader is a failure, not a reason to skip
        ASSERT_NE(renderer_, nullptr) << "no Vulkan loader: install libvulkan1 and mesa-vulkan-drivers";
    }
    void TearDown() override {
        if (renderer_) expect_no_validation_errors(*renderer_);
    }
    static VulkanRenderer& renderer() { return *renderer_; }

    /// Vulkan vs CPU reference, both traversals.
    static void expect_matches_reference(const RenderTestScene& scene, RenderSettings s) {
        renderer().upload(scene.render);
        for (Traversal traversal : {Traversal::Stack, Traversal::Stackless}) {
            s.traversal = traversal;
            expect_close(render_vulkan(renderer(), s), render_reference(scene.render, s), to_string(traversal).c_str());
        }
    }

    static void expect_close(const std::vector<float>& vulkan, const std::vector<float>& reference, const char* what) {
        ImageDiff d = compare_images(vulkan, reference, kFlipThreshold);
        std::printf("%s: mean abs %.3g, max abs %.3g, pixels above %.2g: %.3g%%\n", what, d.mean_abs, d.max_abs,
                    kFlipThreshold, 100 * d.fraction_above);
        EXPECT_LE(d.mean_abs, kMeanTolerance) << what;
        EXPECT_LE(d.max_abs, kMaxTolerance) << what;
        EXPECT_LE(d.fraction_above, kFlipFraction) << what;
    }

    // Tolerances, Vulkan vs CPU. Both run the same tracer source on the same FrameParams, but
    // lavapipe's LLVM may contract a*b+c into FMAs and evaluates sqrt/pow/normalize with its own
    // rounding, while the CPU build forbids contraction (-ffp-contract=off). Measured on lavapipe
    // (Mesa 22.3): mean 1e-7, max 8e-5 (a Blinn-Phong highlight: pow(x, 48) multiplies relative
    // errors by 48), no pixel above 1e-3. Elsewhere a few ulps may move a ray that grazes a
    // silhouette or a shared triangle edge to the other side: that pixel (and what its reflections
    // see) may then differ by up to the whole colour range. Hence: the fraction of pixels off by
    // more than 1e-3 is bounded (flips), the maximum only catches garbage (NaN, a wrong buffer:
    // colours lie in about [0, 1.3]), and the mean catches systematic errors (a wrong shading term
    // moves it by more than 1e-2).
    static constexpr double kMeanTolerance = 1e-3;
    static constexpr float kMaxTolerance = 1.5f;
    static constexpr float kFlipThreshold = 1e-3f;  // far above float noise, far below a visible error
    static constexpr double kFlipFraction = 0.01;   // 1% of the pixels: 30 of 64×48

    static inline VulkanRenderer* renderer_ = nullptr;
};

}  // namespace bvhlab::test
