// py_cancel.h — long work started from Python stops on Ctrl-C and when a progress callable says so,
// and what Python raised is raised again, as itself, once every worker thread has stopped.
#pragma once
#include <atomic>
#include <chrono>
#include <optional>
#include <thread>

#include <pthread.h>
#include <utility>

#include <nanobind/nanobind.h>

#include "bvhlab/cancel.h"

namespace bvhlab::python {

namespace nb = nanobind;

/// Long calls from Python in progress (PyLongCall), those parked, and whether the interpreter is
/// finishing (_finish_long_calls, from bvhlab's atexit handler). A thread still inside one when
/// Python finalizes is ended by pthread_exit as it takes the GIL back, whose unwinding through C++
/// aborts the process ("terminate called without an active exception": Blender 4.3 quit while a
/// daemon thread rendered, probe); let back into Python before that, it may still be writing its
/// traceback when finalization takes stderr (Python's own fatal error, abort). So at exit every
/// call on another thread parks, without the GIL, until the process ends (as Python 3.14 parks
/// daemon threads): at its next look at Ctrl-C or on its way back to Python (LongRelease), and the
/// exit waits for those in progress. The exiting thread's own calls (a later atexit handler's, a
/// finalizer's) run as ever.
struct LongCalls {
    std::atomic<int> alive{0};
    std::atomic<int> parked{0};
    std::atomic<std::thread::id> finisher{};  ///< the thread that runs the finish (set first)
    std::atomic<bool> finishing{false};
};

inline LongCalls& long_calls() {
    static LongCalls calls;
    return calls;
}

/// This thread's nesting of PyLongCall, and whether its outermost is counted.
struct ThreadCalls {
    int depth = 0;
    bool counted = false;
};

inline ThreadCalls& thread_calls() {
    static thread_local ThreadCalls calls;
    return calls;
}

/// Whether the interpreter finishes and this thread is not the one finishing it.
inline bool should_park() {
    return long_calls().finishing.load() && long_calls().finisher.load() != std::this_thread::get_id();
}

/// Sleeps until the process ends, the GIL released first where this thread holds it.
[[noreturn]] inline void park() {
    long_calls().parked.fetch_add(1);
    if (PyGILState_Check()) (void)PyEval_SaveThread();
    for (;;) std::this_thread::sleep_for(std::chrono::hours(1));
}

/// One long call from Python, counted while it lasts (not on the finishing thread): made and
/// destroyed with the GIL held (so the finish, which holds the GIL, sees it counted or not yet
/// begun). A thread counts once however many are nested, as it parks once.
struct PyLongCall {
    PyLongCall() {
        ThreadCalls& t = thread_calls();
        if (t.depth++ != 0) return;
        t.counted = long_calls().finisher.load() != std::this_thread::get_id();
        if (t.counted) long_calls().alive.fetch_add(1);
    }
    ~PyLongCall() {
        ThreadCalls& t = thread_calls();
        if (--t.depth == 0 && t.counted) long_calls().alive.fetch_sub(1);
    }
    PyLongCall(const PyLongCall&) = delete;
    PyLongCall& operator=(const PyLongCall&) = delete;
};

/// The GIL released for a call that may be long: counted (PyLongCall) and, while the interpreter
/// finishes, parked on its way back, before the GIL would be taken again (also when unwinding).
class LongRelease {
public:
    LongRelease() = default;
    LongRelease(const LongRelease&) = delete;
    LongRelease& operator=(const LongRelease&) = delete;

private:
    struct ParkOnReturn {
        ~ParkOnReturn() {
            if (should_park()) park();
        }
    };
    PyLongCall counted_;  // constructed first, with the GIL; destroyed last, with it again
    nb::gil_scoped_release release_;
    ParkOnReturn park_;
};

/// The atexit handler's work (_core._finish_long_calls): marks the interpreter as finishing, from
/// this thread, and waits up to `seconds` until every counted call has parked. True when all have.
inline bool finish_long_calls(double seconds) {
    LongCalls& calls = long_calls();
    calls.finisher.store(std::this_thread::get_id());
    calls.finishing.store(true);  // with the GIL: a call is counted already, or begins after
    const auto settled = [&calls] { return calls.alive.load() <= calls.parked.load(); };
    {
        nb::gil_scoped_release release;
        const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
        while (!settled() && std::chrono::steady_clock::now() < until)
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    // a parked call keeps its objects alive: nanobind's leak report at exit would blame them
    if (calls.parked.load() > 0) nb::set_leak_warnings(false);
    return settled();
}

/// A forked child has only the forking thread, outside any call: the parent's calls in progress
/// are not its own (counted, its exit waited 10 s for them). Registered once, at import.
inline void forget_long_calls_in_forked_children() {
    pthread_atfork(nullptr, nullptr, [] { long_calls().alive.store(0); });
}

/// The check of a Cancellation (cancel.h) for work started from Python. Runs on the calling
/// thread, with the GIL released around it: it takes the GIL, runs Python's signal handlers
/// (Ctrl-C raises KeyboardInterrupt there) and then the progress callable, if any. The callable's
/// result is taken by its truth value (None means go on); anything raised is kept, the work is
/// told to stop, and rethrow() raises it after the work has returned.
class PyStopCheck {
public:
    explicit PyStopCheck(nb::object progress = nb::none()) : progress_(std::move(progress)) {}

    /// True to stop. `fraction` is passed to the progress callable. While the interpreter
    /// finishes, a call on another thread than the finishing one parks instead (park).
    bool operator()(double fraction) {
        if (should_park()) park();
        nb::gil_scoped_acquire gil;
        if (error_) return true;
        if (PyErr_CheckSignals() != 0) return keep_error();
        if (progress_.is_none()) return false;
        PyObject* result = PyObject_CallFunction(progress_.ptr(), "d", fraction);
        if (!result) return keep_error();
        const int go_on = Py_IsNone(result) ? 1 : PyObject_IsTrue(result);
        Py_DECREF(result);
        if (go_on < 0) return keep_error();  // e.g. the truth value of a numpy array is ambiguous
        return go_on == 0;
    }

    bool has_error() const { return error_.has_value(); }

    /// Raises the kept Python exception, if any (call with the GIL held, after the work stopped).
    void rethrow() {
        if (error_) {
            nb::python_error e = std::move(*error_);
            error_.reset();
            throw e;
        }
    }

private:
    bool keep_error() {
        error_.emplace();  // takes the current Python error indicator
        return true;
    }

    nb::object progress_;
    std::optional<nb::python_error> error_;
};

}  // namespace bvhlab::python
