// cancel.h — stopping long work from outside (Ctrl-C in Python, Esc in Blender, a progress
// callback that says stop), promptly and from any thread of the work (Embree's progress-monitor
// shape: the caller's function decides, the library stops).
#pragma once
#include <atomic>
#include <chrono>
#include <exception>
#include <functional>

namespace bvhlab {

/// Shared by every thread of one long operation (a build, a render, a batch of rays).
/// Worker threads call stop_requested() between small units of work (an atomic load); the thread
/// that started the operation also calls poll(), which at most every `interval` runs the caller's
/// check (Python's signal handlers, a progress callback) and requests a stop when it says so.
/// A Cancellation never throws from poll(): the check must catch what it raises (see
/// core_cpp/python/py_cancel.h, which keeps a Python exception until the work has stopped).
class Cancellation {
public:
    /// Returns true to stop. Called only from the thread that calls poll().
    using Check = std::function<bool()>;

    Cancellation() = default;
    explicit Cancellation(Check check, std::chrono::milliseconds interval = std::chrono::milliseconds(20))
        : check_(std::move(check)), interval_(interval) {}
    Cancellation(const Cancellation&) = delete;
    Cancellation& operator=(const Cancellation&) = delete;

    bool stop_requested() const { return stop_.load(std::memory_order_relaxed); }
    void request_stop() { stop_.store(true, std::memory_order_relaxed); }

    /// From the calling thread only: runs the check when `interval` has passed since the last one
    /// (the first call checks at once). Returns stop_requested().
    bool poll() {
        if (check_ && !stop_requested()) {
            auto now = std::chrono::steady_clock::now();
            if (!checked_ || now - last_ >= interval_) {
                checked_ = true;
                last_ = now;
                if (check_()) request_stop();
            }
        }
        return stop_requested();
    }

private:
    Check check_;
    std::chrono::milliseconds interval_{20};
    std::chrono::steady_clock::time_point last_{};
    bool checked_ = false;
    std::atomic<bool> stop_{false};
};

/// Thrown by an operation that stopped because its Cancellation asked it to.
struct Cancelled : std::exception {
    const char* what() const noexcept override { return "cancelled"; }
};

}  // namespace bvhlab
