// Bad input gets a clear std::invalid_argument naming what is wrong; cancellation stops a build.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <tuple>
#include <utility>
#include <vector>
#include <limits>
#include <string>

#include "bvhlab/bvh.h"
#include "bvhlab/cancel.h"
#include "bvhlab/coordinate_range.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"
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

// make_prim_refs checks four lanes at a time and the last triangle on its own: every one of the
// nine coordinates of the first, a middle and the last triangle is checked, for NaN, ±inf and
// a value past the coordinate range.
TEST(BadInput, EveryCoordinateSlotIsChecked) {
    const float bad[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                         -std::numeric_limits<float>::infinity(), 2 * kMaxCoordinate};
    for (int tri : {0, 6, 12}) {
        for (int k = 0; k < 9; ++k)
            for (float value : bad) {
                auto scene = test::random_scene(13, 0, 7);
                scene.triangles[9 * tri + k] = value;
                expect_invalid([&] { build_bvh(scene.view()); }, "triangle " + std::to_string(tri) + " has a");
            }
    }
}

TEST(BadInput, SphereRadiusMustBePositiveAndFinite) {
    for (float r : {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    6.9e-41f, 0x1p-61f}) {  // below kMinRadius (2^-60) r² underflows
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

// Issue 8.5: coordinates past ±2^40 overflow the float32 tests (coordinate_range.h): refused.
TEST(BadInput, CoordinatesOutsideTheRangeNameThePrimitive) {
    auto scene = test::random_scene(20, 5, 1);
    scene.triangles[9 * 11 + 7] = 1e13f;
    expect_invalid([&] { build_bvh(scene.view()); }, "triangle 11 has a vertex coordinate outside the supported range");
    expect_invalid([&] { validate(scene.view()); }, "triangle 11");
    scene.triangles[9 * 11 + 7] = kMaxCoordinate;  // the edge itself is inside
    EXPECT_NO_THROW(build_bvh(scene.view()));
    scene.spheres[4 * 3 + 3] = 2e19f;
    expect_invalid([&] { build_bvh(scene.view()); }, "sphere 3 (centre ± radius) reaches outside");
    scene.spheres[4 * 3 + 3] = 0x1p20f, scene.spheres[4 * 3] = -kMaxCoordinate;  // centre on the edge, radius past it
    expect_invalid([&] { build_bvh(scene.view()); }, "sphere 3");
}

TEST(BadInput, RaysOutsideTheRangeAreRefusedByIndex) {
    auto scene = test::random_scene(50, 5, 1);
    Bvh bvh = build_bvh(scene.view());
    std::vector<float> o(3 * 4, 1.0f), d(3 * 4, 1.0f), t(4);
    std::vector<std::int32_t> prim(4);
    auto run = [&] { intersect_batch(bvh, {o.data(), d.data(), 4}, {t.data(), prim.data()}, Traversal::Stack); };
    EXPECT_NO_THROW(run());
    o[3 * 2 + 1] = 2e12f;
    expect_invalid(run, "ray 2 starts outside the supported coordinate range");
    o[3 * 2 + 1] = 1.0f;
    d[3 * 1] = d[3 * 1 + 1] = d[3 * 1 + 2] = 0.0f;
    expect_invalid(run, "ray 1: the largest |component| of a direction must be in");
    d[3 * 1] = 1e-30f;
    expect_invalid(run, "ray 1");
    d[3 * 1] = std::numeric_limits<float>::quiet_NaN(), d[3 * 1 + 1] = 1.0f;
    expect_invalid(run, "ray 1: origin and direction must be finite");
}

// A ray is scaled by a power of two for the arithmetic: exact, so hits are bit for bit the same.
TEST(BadInput, DirectionLengthDoesNotChangeHits) {
    auto scene = test::random_scene(300, 40, 2);
    Bvh bvh = build_bvh(scene.view());
    std::vector<float> o, d;
    for (std::uint32_t i = 0; i < 500; ++i) {
        o.insert(o.end(), {float(i % 10), float(i % 7) + 0.5f, -3.0f});
        d.insert(d.end(), {0.01f * float(i % 13), 0.02f * float(i % 5), 0.9f});
    }
    auto run = [&](float scale) {
        std::vector<float> ds(d), t(500), u(500), v(500);
        for (float& x : ds) x *= scale;
        std::vector<std::int32_t> prim(500);
        intersect_batch(bvh, {o.data(), ds.data(), 500}, {t.data(), prim.data(), nullptr, u.data(), v.data()},
                        Traversal::Stack);
        for (float& x : t) x *= scale;
        return std::tuple(t, prim, u, v);
    };
    const auto unit = run(1.0f);
    int hits = 0;
    for (std::int32_t p : std::get<1>(unit)) hits += p >= 0;
    EXPECT_GT(hits, 50);
    for (float scale : {0x1p-79f, 0x1p-30f, 0x1p20f, 0x1p79f}) EXPECT_TRUE(run(scale) == unit) << scale;
}

// Issue 8.2: the last progress call (1.0) may cancel too.
TEST(BadInput, ProgressFalseAtTheEndCancels) {
    auto scene = test::random_scene(3000, 10, 1);
    for (std::uint32_t threads : {1u, 2u}) {
        BuildConfig c;
        c.threads = threads;
        c.progress = [](double f) { return f < 1.0; };
        EXPECT_THROW(build_bvh(scene.view(), c), BuildCancelled);
    }
    BuildConfig c;
    c.progress = [](double) { return false; };
    EXPECT_THROW(build_bvh(test::Scene{}.view(), c), BuildCancelled);  // an empty build reports 1.0 too
}

// Issue 8.12: a batch of rays stops when its Cancellation says so, on every thread.
TEST(BadInput, CancellationStopsARayBatch) {
    auto scene = test::random_scene(2000, 0, 1);
    Bvh bvh = build_bvh(scene.view());
    const std::size_t n = 200000;
    std::vector<float> o(3 * n, 1.0f), d(3 * n), t(n, -1.0f);
    for (std::size_t i = 0; i < n; ++i) d[3 * i] = 1.0f, d[3 * i + 1] = float(i % 17) - 8.0f, d[3 * i + 2] = 0.5f;
    std::vector<std::int32_t> prim(n);
    for (std::uint32_t threads : {1u, 2u}) {
        int polls = 0;
        Cancellation cancel([&] { return ++polls == 3; }, std::chrono::milliseconds(0));
        std::fill(t.begin(), t.end(), -1.0f);
        EXPECT_THROW(intersect_batch(bvh, {o.data(), d.data(), n}, {t.data(), prim.data()}, Traversal::Stack, threads,
                                     nullptr, &cancel),
                     Cancelled);
        EXPECT_EQ(polls, 3);
        EXPECT_GT(std::count(t.begin(), t.end(), -1.0f), std::ptrdiff_t(n / 2)) << "stopped early, threads " << threads;
    }
}

// A chunk of costly rays (1,024, one task) took seconds to see a Ctrl-C (helper probe: 3.4 s on
// the stack walk over 200,000 overlapping triangles): the walks look at the cancellation inside
// a chunk too, every 16 rays (per-ray walks) or every piece of 256 (the wide batch). The third
// poll says stop: the first is the batch's before it starts, the second the chunk's, the third
// the first look inside it; before, the chunk ran to its end (all 1,024 rays traced).
TEST(BadInput, CancellationIsSeenInsideAChunk) {
    auto scene = test::random_scene(2000, 0, 1);
    Bvh bvh = build_bvh(scene.view());
    const WideBvh wide = make_wide(bvh);
    const std::size_t n = 1024;
    std::vector<float> o(3 * n, 1.0f), d(3 * n), t(n);
    for (std::size_t i = 0; i < n; ++i) d[3 * i] = 1.0f, d[3 * i + 1] = float(i % 17) - 8.0f, d[3 * i + 2] = 0.5f;
    std::vector<std::int32_t> prim(n);
    for (auto [mode, most] : {std::pair{Traversal::Stack, 16}, {Traversal::Stackless, 16}, {Traversal::Wide, 256}}) {
        int polls = 0;
        Cancellation cancel([&] { return ++polls == 3; }, std::chrono::milliseconds(0));
        std::fill(t.begin(), t.end(), -1.0f);
        EXPECT_THROW(intersect_batch(bvh, {o.data(), d.data(), n}, {t.data(), prim.data()}, mode, 1, &wide, &cancel),
                     Cancelled);
        EXPECT_EQ(polls, 3);
        EXPECT_LE(n - std::size_t(std::count(t.begin(), t.end(), -1.0f)), std::size_t(most)) << int(mode);
    }
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
    for (std::uint32_t block : {0u, 3u, 6u, 128u, 0x80000000u}) {
        c = {};
        c.sah_block = block;
        expect_invalid([&] { build_bvh(scene.view(), c); }, "sah_block must be a power of two");
    }
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
        c.progress = [&](double) {
            ++calls;
            return false;
        };
        EXPECT_THROW(build_bvh(scene.view(), c), BuildCancelled);
        EXPECT_EQ(calls, 1);  // nothing is reported after a cancel
    }
}

TEST(BadInput, ProgressReachesOne) {
    auto scene = test::random_scene(1000, 0, 1);
    BuildConfig c;
    double last = -1;
    c.progress = [&](double f) {
        EXPECT_GE(f, last);
        last = f;
        return true;
    };
    build_bvh(scene.view(), c);
    EXPECT_EQ(last, 1.0);
}

}  // namespace
