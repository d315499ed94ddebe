// deferred_parts.cpp — build_deferred: the parts below the top of the tree, from a queue that the
// tasks themselves fill (a range split by one task adds the ranges below it).
#include "deferred_parts.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <vector>

#include "assemble.h"
#include "bvhlab/thread_pool.h"
#include "bvhlab/work_trace.h"

namespace bvhlab {
namespace {

/// A deferred range and the subtree to build for it.
struct Job {
    const DeferredRange* range = nullptr;
    Subtree* out = nullptr;
    std::uint32_t size() const { return range->item.range.size(); }
};

/// The queue of one build_deferred call, shared by the threads of one pool run.
class PartQueue {
public:
    PartQueue(BuildShared& shared, std::uint32_t part_size, const std::function<void()>& poll)
        : shared_(shared), part_size_(part_size), poll_(poll) {}

    /// Queues every deferred range of `s` (sizing s.parts).
    void add_ranges_of(Subtree& s) {
        s.parts.resize(s.deferred.size());
        {
            std::lock_guard<std::mutex> lock(mutex_);
            for (std::size_t k = 0; k < s.deferred.size(); ++k) {
                heap_.push_back({&s.deferred[k], &s.parts[k]});
                std::push_heap(heap_.begin(), heap_.end(), smaller);
            }
        }
        more_.notify_all();
    }

    /// One thread's work: jobs until the queue is empty and no job is running (a running one may
    /// still add), or a stop is asked.
    void work(unsigned slot, SplitScratch& scratch) {
        for (Job job; next(slot, job);) {
            BVHLAB_WORK_MARK("queue");  // taking the job (or waiting for one)
            try {
                build(job, slot, scratch);
            } catch (...) {
                shared_.cancel.request_stop();
                done();
                throw;
            }
            done();
            BVHLAB_WORK_MARK("job %u %u", job.range->item.range.begin, job.range->item.range.end);
        }
    }

private:
    static bool smaller(const Job& a, const Job& b) { return a.size() < b.size(); }

    /// Takes the largest queued job into `job` (as running); false when there is no more work.
    bool next(unsigned slot, Job& job) {
        std::unique_lock<std::mutex> lock(mutex_);
        for (;;) {
            if (shared_.cancel.stop_requested()) return false;
            if (!heap_.empty()) {
                std::pop_heap(heap_.begin(), heap_.end(), smaller);
                job = heap_.back();
                heap_.pop_back();
                ++running_;
                return true;
            }
            if (running_ == 0) return false;
            more_.wait_for(lock, std::chrono::milliseconds(2));
            if (slot == 0 && poll_) {  // the calling thread keeps the cancellation prompt
                lock.unlock();
                poll_();
                lock.lock();
            }
        }
    }

    void done() {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            --running_;
        }
        more_.notify_all();
    }

    void build(const Job& job, unsigned slot, SplitScratch& scratch) {
        WorkItem root = job.range->item;
        root.second_child = false;  // its parent lives in another subtree, which already points at it
        root.bounds.bins = adopt_bins(scratch, job.range->bins);
        const bool split_only = job.size() > part_size_;
        Subtree& out = *job.out;
        build_subtree(shared_, scratch, root, out, {split_only ? part_size_ : 0, slot == 0, nullptr});
        if (shared_.cancel.stop_requested()) return;
        // a subtree with placeholders gets its boxes from its children when assembled
        if (shared_.method.bottom_up_boxes && out.deferred.empty()) fill_boxes_from_children(out.nodes);
        pack_unpacked(shared_, out);
        if (!out.deferred.empty()) add_ranges_of(out);
    }

    BuildShared& shared_;
    const std::uint32_t part_size_;
    const std::function<void()>& poll_;
    std::mutex mutex_;
    std::condition_variable more_;
    std::vector<Job> heap_;  ///< by size (std::push_heap)
    unsigned running_ = 0;
};

}  // namespace

void build_deferred(BuildShared& shared, Subtree& top, std::uint32_t part_size, unsigned threads,
                    const std::function<void()>& poll) {
    PartQueue queue(shared, part_size, poll);
    queue.add_ranges_of(top);
    std::vector<SplitScratch> scratch(threads);
    ThreadPool::shared().run(
        threads, threads, [&](std::size_t, unsigned slot) { queue.work(slot, scratch[slot]); }, poll);
}

}  // namespace bvhlab
