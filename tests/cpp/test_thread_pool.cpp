// The shared thread pool: every index runs once, exceptions come back to the caller after every
// thread has left, nested and concurrent calls finish, the waiting caller keeps polling.
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

#include "bvhlab/thread_pool.h"

using namespace bvhlab;

TEST(ThreadPool, EveryIndexOnceOnAnyThreadCount) {
    for (unsigned threads : {0u, 1u, 2u, 5u}) {
        std::vector<std::atomic<int>> hits(1000);
        ThreadPool::shared().run(hits.size(), threads, [&](std::size_t i, unsigned slot) {
            EXPECT_LT(slot, ThreadPool::resolve(threads));
            ++hits[i];
        });
        for (auto& h : hits) ASSERT_EQ(h.load(), 1);
    }
}

TEST(ThreadPool, FirstExceptionRethrownAfterEveryThreadLeft) {
    std::atomic<int> inside{0}, done{0};
    EXPECT_THROW(ThreadPool::shared().run(200, 4,
                                          [&](std::size_t i, unsigned) {
                                              ++inside;
                                              if (i == 3) throw std::runtime_error("task failed");
                                              std::this_thread::sleep_for(std::chrono::microseconds(200));
                                              ++done, --inside;
                                          }),
                 std::runtime_error);
    EXPECT_EQ(inside.load(), 1);  // only the failed task did not leave normally: no thread still runs
    EXPECT_LT(done.load(), 200);  // indices stop being handed out after the failure
}

TEST(ThreadPool, NestedAndConcurrentCallsFinish) {
    std::atomic<int> total{0};
    auto outer = [&] {
        ThreadPool::shared().run(8, 0, [&](std::size_t, unsigned) {
            ThreadPool::shared().run(8, 0, [&](std::size_t, unsigned) { ++total; });
        });
    };
    std::thread a(outer), b(outer);
    outer();
    a.join(), b.join();
    EXPECT_EQ(total.load(), 3 * 64);
}

TEST(ThreadPool, TheWaitingCallerPolls) {
    // A task on a helper thread waits until the caller has polled three times: the call can only
    // end if the caller keeps polling while it waits.
    std::atomic<bool> release{false}, helper_ran{false};
    std::atomic<int> polls{0};
    for (int attempt = 0; attempt < 20 && !helper_ran; ++attempt) {
        ThreadPool::shared().run(
            64, 2,
            [&](std::size_t, unsigned slot) {
                if (slot == 0) {  // the caller is slow, so that a helper joins
                    std::this_thread::sleep_for(std::chrono::milliseconds(2));
                    return;
                }
                helper_ran = true;
                while (!release) std::this_thread::yield();
            },
            [&] {
                if (++polls >= 3) release = true;
            },
            std::chrono::milliseconds(1));
    }
    if (!helper_ran) GTEST_SKIP() << "no helper thread joined (one hardware thread?)";
    EXPECT_GE(polls.load(), 3);
}
