// Bad input gets a clear std::invalid_argument naming what is wrong; cancellation stops a build.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "bvhlab/bvh.h"
#include "test_scenes.h"

using namespace bvhlab;

namespace {

/// Runs f, expects std::invalid_argument whose message contains `needle`.
template <class F>
void expect_invalid(F&& f, const std::string& needle) {
    try {
        f();
        ADD_FAILURE() << "no exception; expected one mentioning '" << needle << "'";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
}

TEST(BadInput, NanOrInfiniteVertexNamesTheTriangle) {
    auto scene = test::random_scene(100, 10, 1);
    scene.triangles[9 * 37 + 4] = std::numeric_limits<float>::quiet_NaN();
    expect_invalid([&] { build_bvh(scene.view()); }, "triangle 37");
    scene.triangles[9 * 37 + 4] = 0;
    scene.triangles[9 * 5] = -std::numeric_limits<float>::infinity();
    expect_invalid([&] { build_bvh(scene.view()); }, "triangle 5");
}

TEST(BadInput, SphereRadiusMustBePositiveAndFinite) {
    for (float r : {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        auto scene = test::random_scene(10, 10, 1);
        scene.spheres[4 * 3 + 3] = r;
        expect_invalid([&] { build_bvh(scene.view()); }, "sphere 3");
    }
    auto scene = test::random_scene(10, 10, 1);
    scene.spheres[4 * 2 + 1] = std::numeric_limits<float>::quiet_NaN();
    expect_invalid([&] { build_bvh(scene.view()); }, "sphere 2");
    scene = test::random_scene(10, 10, 1);
    scene.spheres[4 * 2] = 3e38f, scene.spheres[4 * 2 + 3] = 3e38f;
    expect_invalid([&] { build_bvh(scene.view()); }, "sphere 2");
}

TEST(BadInput, ConfigOutOfRange) {
    auto scene = test::random_scene(10, 0, 1);
    for (std::uint32_t bins : {0u, 1u, 257u, 100000u}) {
        BuildConfig c;
        c.bins = bins;
        expect_invalid([&] { build_bvh(scene.view(), c); }, "bins");
    }
    BuildConfig c;
    c.max_leaf_size = 0;
    expect_invalid([&] { build_bvh(scene.view(), c); }, "max_leaf_size");
    c = {};
    c.traversal_cost = std::numeric_limits<float>::quiet_NaN();
    expect_invalid([&] { build_bvh(scene.view(), c); }, "SAH costs");
}

TEST(BadInput, UnknownNamesListTheValidOnes) {
    expect_invalid([] { parse_split_method("sha"); }, "median mean midpoint sah sweep_sah lbvh");
    expect_invalid([] { parse_axis_policy("longest"); }, "largest random best");
    EXPECT_EQ(parse_split_method("sweep_sah"), SplitMethod::SweepSah);
    EXPECT_EQ(to_string(AxisPolicy::Best), "best");
}

TEST(BadInput, ProgressCanCancel) {
    auto scene = test::random_scene(200000, 0, 1);
    for (std::uint32_t threads : {1u, 2u}) {
        BuildConfig c;
        c.threads = threads;
        int calls = 0;
        c.progress = [&](double) { ++calls; return false; };
        EXPECT_THROW(build_bvh(scene.view(), c), BuildCancelled);
        EXPECT_EQ(calls, 1);  // nothing is reported after a cancel
    }
}

TEST(BadInput, ProgressReachesOne) {
    auto scene = test::random_scene(1000, 0, 1);
    BuildConfig c;
    double last = -1;
    c.progress = [&](double f) { EXPECT_GE(f, last); last = f; return true; };
    build_bvh(scene.view(), c);
    EXPECT_EQ(last, 1.0);
}

}  // namespace
