// Build progress (BuildConfig::progress, cancel.h): reported often, in order, last 1.0; a callback
// that says stop cancels the build on any thread count; the references pass polls and stops; an
// exception from the callback comes out as itself.
#include <gtest/gtest.h>

#include <cstring>
#include <stdexcept>
#include <vector>

#include "bvhlab/big_vector.h"
#include "bvhlab/bvh.h"
#include "bvhlab/cancel.h"
#include "bvhlab/geometry.h"
#include "test_scenes.h"

using namespace bvhlab;
using bvhlab::test::random_scene;

namespace {

TEST(Progress, ReportedOftenAndStopsTheBuild) {
    auto scene = random_scene(120000, 1000, 21);
    for (std::uint32_t threads : {1u, 2u, 8u}) {  // 8: nodes of the top split one per task (build_deferred)
        BuildConfig c;
        c.threads = threads;
        std::vector<double> seen;
        c.progress = [&](double f) {
            seen.push_back(f);
            return true;
        };
        build_bvh(scene.view(), c);
        ASSERT_GE(seen.size(), 2u);
        EXPECT_EQ(seen.back(), 1.0);
        for (std::size_t i = 1; i < seen.size(); ++i) EXPECT_LE(seen[i - 1], seen[i]);
        // A callback that says stop cancels the build, whichever thread is busy where.
        int calls = 0;
        c.progress = [&](double) { return ++calls < 2; };
        EXPECT_THROW(build_bvh(scene.view(), c), BuildCancelled) << threads << " threads";
    }
}

// make_prim_refs polls the build's Cancellation on the calling thread before each chunk: a stop
// asked at the first poll skips every chunk (a large mesh answered Esc only after the whole
// pass), and no thread begins a chunk once a stop is asked.
TEST(Progress, TheReferencesPassPollsAndStops) {
    auto scene = random_scene(200000, 100, 23);  // several chunks
    const BigVector<PrimRef> all = make_prim_refs(scene.view(), 1);
    int checks = 0;
    Cancellation first_poll([&] { return ++checks >= 1; });
    EXPECT_TRUE(make_prim_refs(scene.view(), 1, nullptr, &first_poll).empty());
    EXPECT_EQ(checks, 1);  // the calling thread runs every chunk; it stopped before the first
    for (std::uint32_t threads : {1u, 2u, 3u}) {
        Cancellation stopped;
        stopped.request_stop();
        EXPECT_TRUE(make_prim_refs(scene.view(), threads, nullptr, &stopped).empty()) << threads;
        Cancellation go([&] { return false; });
        const BigVector<PrimRef> refs = make_prim_refs(scene.view(), threads, nullptr, &go);
        ASSERT_EQ(refs.size(), all.size()) << threads;
        EXPECT_EQ(std::memcmp(refs.data(), all.data(), all.size() * sizeof(PrimRef)), 0) << threads;
    }
}

TEST(Progress, AnExceptionFromTheCallbackComesOutAsItself) {
    auto scene = random_scene(120000, 1000, 22);
    for (std::uint32_t threads : {1u, 2u, 3u, 8u}) {
        BuildConfig c;
        c.threads = threads;
        int calls = 0;
        c.progress = [&](double) -> bool {
            if (++calls == 2) throw std::runtime_error("callback failed");
            return true;
        };
        try {
            build_bvh(scene.view(), c);
            ADD_FAILURE() << "no exception";
        } catch (const std::runtime_error& e) { EXPECT_STREQ(e.what(), "callback failed"); }
    }
}

}  // namespace
