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

/// std::timed_mutex plus the id of the thread holding it. Satisfies Lockable and TimedLockable, so
/// std::lock_guard and std::unique_lock work on it.
class OwnedMutex {
public:
    /// `what` names the guarded thing in the ReentrantCall message ("this render job").
    explicit OwnedMutex(std::string what) : what_(std::move(what)) {}

    void lock() {
        refuse_reentry();
        mutex_.lock();
        owner_.store(std::this_thread::get_id(), std::memory_order_relaxed);
    }
    bool try_lock() { return try_lock_for(std::chrono::milliseconds(0)); }
    template <class Rep, class Period>
    bool try_lock_for(const std::chrono::duration<Rep, Period>& wait) {
        refuse_reentry();
        if (!mutex_.try_lock_for(wait)) return false;
        owner_.store(std::this_thread::get_id(), std::memory_order_relaxed);
        return true;
    }
    void unlock() {
        owner_.store(std::thread::id(), std::memory_order_relaxed);
        mutex_.unlock();
    }

    /// True on the thread that holds the lock. Only that thread can ever read its own id here, so
    /// a relaxed load is exact for the question "do I hold it?".
    bool held_by_this_thread() const { return owner_.load(std::memory_order_relaxed) == std::this_thread::get_id(); }

private:
    void refuse_reentry() const {
        if (held_by_this_thread())
            throw ReentrantCall(what_ +
                                " is busy on this thread (a call from inside its own work, such as its "
                                "progress callback); call it after that work returns");
    }

    std::timed_mutex mutex_;
    std::atomic<std::thread::id> owner_{};
    std::string what_;
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
/// may throw, before anything is locked).
inline std::unique_lock<OwnedMutex> lock_in_slices(OwnedMutex& mutex) {
    std::unique_lock<OwnedMutex> lock(mutex, std::defer_lock);
    while (!lock.try_lock_for(std::chrono::milliseconds(20)))
        if (const WaitCheck::Fn check = WaitCheck::current()) check();
    return lock;
}

}  // namespace bvhlab
