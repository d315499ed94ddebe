// thread_pool.h — the one pool of worker threads that builds, ray batches and the CPU renderer share.
//
//     ThreadPool::shared().run(count, threads, [&](std::size_t i, unsigned slot) { ... });
//
// runs the task for every index in [0, count) on at most `threads` threads, the calling thread
// included (it always takes part, so nested and concurrent calls cannot deadlock), and returns when
// all have finished. `slot` numbers the threads of one call 0..threads-1 (the caller is 0): index
// per-thread scratch with it. Indices are handed out in increasing order, one at a time, so put
// the largest tasks first.
#pragma once
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace bvhlab {

class Cancellation;

class ThreadPool {
public:
    using Task = std::function<void(std::size_t index, unsigned slot)>;

    /// A pool with `workers` threads besides the callers.
    explicit ThreadPool(unsigned workers);
    ~ThreadPool();
    ThreadPool(const ThreadPool&) = delete;
    ThreadPool& operator=(const ThreadPool&) = delete;

    /// The process-wide pool: one worker per hardware thread but one, started on first use and
    /// never destroyed (worker threads must not outlive the statics they use at exit).
    static ThreadPool& shared();

    /// Hardware threads, at least 1.
    static unsigned hardware_threads();

    /// `threads` as BuildConfig and the batch calls spell it: 0 means every hardware thread.
    static unsigned resolve(unsigned threads) { return threads ? threads : hardware_threads(); }

    /// Runs task(i, slot) for every i in [0, count) on at most `threads` threads (0 = all).
    /// Exceptions never escape a worker: the first one a task throws stops the handing out of
    /// further indices and is rethrown here once every thread has left the call.
    /// `while_waiting`, if set, is called on this thread every `wait_interval` while it waits for
    /// other threads to finish (for cancellation checks and progress that must stay prompt).
    void run(std::size_t count, unsigned threads, const Task& task, const std::function<void()>& while_waiting = {},
             std::chrono::milliseconds wait_interval = std::chrono::milliseconds(5));

    /// run() for work that a build may stop: `cancel` (may be null) is polled on the calling
    /// thread (slot 0) before each of its tasks and while it waits; once a stop is asked, no
    /// further task begins. Returns false when a stop was asked (some tasks did not run).
    bool run_until_stopped(std::size_t count, unsigned threads, const Task& task, Cancellation* cancel);

private:
    struct Job;
    void worker_loop();
    static void work_on(Job& job, unsigned slot);

    std::mutex mutex_;
    std::condition_variable wake_;
    std::deque<std::shared_ptr<Job>> jobs_;  ///< calls that may still take helpers
    std::atomic<std::uint64_t> posted_{0};   ///< jobs ever posted: idle workers spin on it briefly
    bool stopping_ = false;
    std::vector<std::thread> workers_;
};

}  // namespace bvhlab
