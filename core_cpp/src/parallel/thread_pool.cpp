#include "bvhlab/thread_pool.h"

#include "bvhlab/cancel.h"
#include "bvhlab/work_trace.h"

#include <algorithm>
#include <exception>

namespace bvhlab {
namespace {

/// How long a thread waiting for the others spins before it sleeps.
constexpr std::chrono::microseconds kSpin(200);

#ifdef BVHLAB_WORK_TRACE
std::atomic<unsigned> trace_runs{0};  ///< numbers the calls of run() for the marks
#endif

}  // namespace

/// One call of run(): indices still to hand out, the threads inside it, the first exception.
struct ThreadPool::Job {
    const Task* task = nullptr;
    std::size_t count = 0;
    unsigned helpers_wanted = 0;  ///< threads besides the caller
    std::atomic<std::size_t> next{0};
    std::atomic<bool> failed{false};
    std::mutex mutex;  ///< guards the fields below
    std::condition_variable left;
    unsigned helpers_joined = 0;
    std::atomic<unsigned> helpers_inside{0};  ///< changed under `mutex`; the caller also reads it spinning
    std::exception_ptr error;
    unsigned trace_id = 0;  ///< BVHLAB_WORK_TRACE: this call's number in the marks
};

ThreadPool::ThreadPool(unsigned workers) {
    for (unsigned i = 0; i < workers; ++i) workers_.emplace_back([this] { worker_loop(); });
}

ThreadPool::~ThreadPool() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stopping_ = true;
    }
    wake_.notify_all();
    for (auto& t : workers_) t.join();
}

unsigned ThreadPool::hardware_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

ThreadPool& ThreadPool::shared() {
    static ThreadPool* pool = new ThreadPool(hardware_threads() - 1);  // leaked on purpose, see the header
    return *pool;
}

void ThreadPool::work_on(Job& job, unsigned slot) {
    for (std::size_t i; !job.failed.load(std::memory_order_relaxed) && (i = job.next.fetch_add(1)) < job.count;) {
        try {
            (*job.task)(i, slot);
            BVHLAB_WORK_MARK("task %u %zu", job.trace_id, i);
        } catch (...) {
            std::lock_guard<std::mutex> lock(job.mutex);
            if (!job.error) job.error = std::current_exception();
            job.failed = true;
        }
    }
}

void ThreadPool::worker_loop() {
    for (;;) {
        // Spin a little before sleeping: the builders post many short jobs in a row, and waking a
        // sleeping thread costs tens of microseconds.
        const std::uint64_t seen = posted_.load();
        for (auto start = std::chrono::steady_clock::now();
             posted_.load() == seen && std::chrono::steady_clock::now() - start < kSpin;)
            std::this_thread::yield();
        std::shared_ptr<Job> job;
        unsigned slot = 0;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            wake_.wait(lock, [this] { return stopping_ || !jobs_.empty(); });
            if (stopping_) return;
            job = jobs_.front();
            std::lock_guard<std::mutex> job_lock(job->mutex);
            slot = ++job->helpers_joined;
            ++job->helpers_inside;
            if (job->helpers_joined == job->helpers_wanted) jobs_.pop_front();
        }
        BVHLAB_WORK_MARK("idle");  // the wait for this job
        work_on(*job, slot);
        std::lock_guard<std::mutex> job_lock(job->mutex);
        if (--job->helpers_inside == 0) job->left.notify_all();
        BVHLAB_WORK_MARK("idle");  // leaving it
    }
}

void ThreadPool::run(std::size_t count, unsigned threads, const Task& task, const std::function<void()>& while_waiting,
                     std::chrono::milliseconds wait_interval) {
    if (count == 0) return;
    auto job = std::make_shared<Job>();
    job->task = &task;
    job->count = count;
    job->helpers_wanted =
        static_cast<unsigned>(std::min<std::size_t>({std::size_t(resolve(threads) - 1), workers_.size(), count - 1}));
#ifdef BVHLAB_WORK_TRACE
    job->trace_id = ++trace_runs;
    BVHLAB_WORK_MARK("run %u %u %zu", job->trace_id, job->helpers_wanted + 1, count);  // the serial part before it
#endif
    if (job->helpers_wanted > 0) {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            jobs_.push_back(job);
        }
        posted_.fetch_add(1);
        wake_.notify_all();
    }
    work_on(*job, 0);
    if (job->helpers_wanted > 0) {
        // Spin a little before sleeping, as the workers do: a helper still inside usually leaves
        // within microseconds (the top of a build runs many short passes in a row), and a sleeping
        // caller is woken late. Sponza on two threads: the passes of the top 5.9 -> 5.4 ms
        // (median of 8 interleaved pairs), the build about 0.5 ms faster.
        for (auto start = std::chrono::steady_clock::now();
             job->helpers_inside.load() > 0 && std::chrono::steady_clock::now() - start < kSpin;)
            std::this_thread::yield();
        {
            std::lock_guard<std::mutex> lock(mutex_);  // no thread may join once the work is gone
            auto it = std::find(jobs_.begin(), jobs_.end(), job);
            if (it != jobs_.end()) jobs_.erase(it);
        }
        std::unique_lock<std::mutex> lock(job->mutex);
        while (job->helpers_inside > 0) {
            if (!while_waiting) {
                job->left.wait(lock);
                continue;
            }
            job->left.wait_for(lock, wait_interval);
            lock.unlock();
            try {
                while_waiting();
            } catch (...) {  // stop the others; rethrown below like a task's exception
                std::lock_guard<std::mutex> error_lock(job->mutex);
                if (!job->error) job->error = std::current_exception();
                job->failed = true;
            }
            lock.lock();
        }
    }
    BVHLAB_WORK_MARK("wait %u", job->trace_id);  // for the helpers to leave
    if (job->error) std::rethrow_exception(job->error);
}

bool ThreadPool::run_until_stopped(std::size_t count, unsigned threads, const Task& task, Cancellation* cancel) {
    if (!cancel) {
        run(count, threads, task);
        return true;
    }
    run(
        count, threads,
        [&](std::size_t i, unsigned slot) {
            if (slot == 0 ? cancel->poll() : cancel->stop_requested()) return;
            task(i, slot);
        },
        [cancel] { cancel->poll(); });
    return !cancel->stop_requested();
}

}  // namespace bvhlab
