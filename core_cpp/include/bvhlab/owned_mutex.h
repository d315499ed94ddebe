// owned_mutex.h — a mutex that knows which thread holds it. Long work (a render job's run) calls
// back into Python while it holds its lock (the progress callable); a callback that calls into
// the same job or renderer again asked for a lock its own thread held, and waited for itself
// forever (issue 39). With OwnedMutex the second call fails at once with ReentrantCall.
#pragma once
#include <atomic>
#include <chrono>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

namespace bvhlab {

/// A call made, on the thread that holds a lock, into what that lock guards (e.g. from a progress
/// callback into the job that is calling it). Python sees a RuntimeError.
class ReentrantCall : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// The order in which a thread may wait for ranked locks (lock_in_slices): a job's first, then the
/// renderer's (a Vulkan job's run holds both while it calls its progress callable). A thread that
/// holds a lock of some rank never waits for one of that rank or below held by another thread:
/// that thread may be waiting for the lock this one holds (a job's callable reading another job,
/// or starting one, while a second thread ran or started that: both waited for good, helper probe
/// 2026-12-07). It asks once and, the lock being busy, gets a ReentrantCall instead.
enum class LockRank : int { None = 0, Job = 1, Renderer = 2 };

/// std::timed_mutex plus the id of the thread holding it. Satisfies Lockable and TimedLockable, so
/// std::lock_guard and std::unique_lock work on it.
class OwnedMutex {
public:
    /// `what` names the guarded thing in the ReentrantCall message ("this render job"); `rank`
    /// orders the waits of lock_in_slices (LockRank).
    explicit OwnedMutex(std::string what, LockRank rank = LockRank::None) : what_(std::move(what)), rank_(rank) {}

    void lock() {
        refuse_reentry();
        mutex_.lock();
        taken();
    }
    bool try_lock() { return try_lock_for(std::chrono::milliseconds(0)); }
    template <class Rep, class Period>
    bool try_lock_for(const std::chrono::duration<Rep, Period>& wait) {
        refuse_reentry();
        if (!mutex_.try_lock_for(wait)) return false;
        taken();
        return true;
    }
    void unlock() {
        --held()[int(rank_)];
        owner_.store(std::thread::id(), std::memory_order_relaxed);
        mutex_.unlock();
    }

    /// True on the thread that holds the lock. Only that thread can ever read its own id here, so
    /// a relaxed load is exact for the question "do I hold it?".
    bool held_by_this_thread() const { return owner_.load(std::memory_order_relaxed) == std::this_thread::get_id(); }

    LockRank rank() const { return rank_; }
    const std::string& what() const { return what_; }

    /// The highest rank of the locks this thread holds (LockRank::None: none ranked).
    static LockRank highest_held() {
        for (int r = int(LockRank::Renderer); r > 0; --r)
            if (held()[r] > 0) return LockRank(r);
        return LockRank::None;
    }

private:
    void refuse_reentry() const {
        if (held_by_this_thread())
            throw ReentrantCall(what_ +
                                " is busy on this thread (a call from inside its own work, such as its "
                                "progress callback); call it after that work returns");
    }
    void taken() {
        owner_.store(std::this_thread::get_id(), std::memory_order_relaxed);
        ++held()[int(rank_)];
    }
    /// This thread's count of held locks by rank.
    static int* held() {
        static thread_local int counts[int(LockRank::Renderer) + 1] = {};
        return counts;
    }

    std::timed_mutex mutex_;
    std::atomic<std::thread::id> owner_{};
    std::string what_;
    LockRank rank_;
};

/// What a thread does between the slices of a wait for an OwnedMutex (lock_in_slices), set for a
/// scope with WaitCheck::Scope: Python's bindings check Ctrl-C there and throw, so that a thread
/// waiting for another thread's long render stays interruptible (it waited for the whole render:
/// 36 s after a Ctrl-C, probe). Per thread; none by default (the wait is a plain one).
class WaitCheck {
public:
    using Fn = void (*)();

    static Fn current() { return slot(); }

    /// Sets `fn` for this thread until the scope ends (the one before is restored).
    class Scope {
    public:
        explicit Scope(Fn fn) : saved_(slot()) { slot() = fn; }
        ~Scope() { slot() = saved_; }
        Scope(const Scope&) = delete;
        Scope& operator=(const Scope&) = delete;

    private:
        Fn saved_;
    };

private:
    static Fn& slot() {
        static thread_local Fn fn = nullptr;
        return fn;
    }
};

/// `mutex` locked, waited for in slices of 20 ms between which this thread's WaitCheck runs (and
/// may throw, before anything is locked). Not waited for where this thread holds a lock of its rank
/// or above (LockRank): asked once, and ReentrantCall where another thread holds it.
inline std::unique_lock<OwnedMutex> lock_in_slices(OwnedMutex& mutex) {
    std::unique_lock<OwnedMutex> lock(mutex, std::defer_lock);
    if (mutex.rank() != LockRank::None && OwnedMutex::highest_held() >= mutex.rank()) {
        if (!lock.try_lock())
            throw ReentrantCall(mutex.what() +
                                " is busy on another thread, and this thread is inside a render's work (a call "
                                "from its progress callable): call it after that work returns");
        return lock;
    }
    while (!lock.try_lock_for(std::chrono::milliseconds(20)))
        if (const WaitCheck::Fn check = WaitCheck::current()) check();
    return lock;
}

}  // namespace bvhlab
