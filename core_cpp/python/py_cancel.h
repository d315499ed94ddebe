// py_cancel.h — long work started from Python stops on Ctrl-C and when a progress callable says so,
// and what Python raised is raised again, as itself, once every worker thread has stopped.
#pragma once
#include <atomic>
#include <chrono>
#include <optional>
#include <thread>
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
/// such call parks at its next look at Ctrl-C, without the GIL, until the process ends (as Python
/// 3.14 parks daemon threads), and the exit waits for that.
struct LongCalls {
    std::atomic<int> alive{0};
    std::atomic<int> parked{0};
    std::atomic<bool> finishing{false};
};

inline LongCalls& long_calls() {
    static LongCalls calls;
    return calls;
}

/// While the interpreter finishes: this thread (in a long call, without the GIL) sleeps until the
/// process ends. Otherwise returns.
inline void park_if_finishing() {
    if (!long_calls().finishing.load()) return;
    long_calls().parked.fetch_add(1);
    for (;;) std::this_thread::sleep_for(std::chrono::hours(1));
}

/// One long call from Python, counted while it lasts: made and destroyed with the GIL held, so
/// when none is counted, none is between releasing the GIL and taking it back. A thread counts
/// once however many are nested (a job's run: its lock's and its check's), as it parks once.
struct PyLongCall {
    PyLongCall() {
        if (depth()++ == 0) long_calls().alive.fetch_add(1);
    }
    ~PyLongCall() {
        if (--depth() == 0) long_calls().alive.fetch_sub(1);
    }
    PyLongCall(const PyLongCall&) = delete;
    PyLongCall& operator=(const PyLongCall&) = delete;

private:
    static int& depth() {
        static thread_local int nested = 0;
        return nested;
    }
};

/// The check of a Cancellation (cancel.h) for work started from Python. Runs on the calling
/// thread, with the GIL released around it: it takes the GIL, runs Python's signal handlers
/// (Ctrl-C raises KeyboardInterrupt there) and then the progress callable, if any. The callable's
/// result is taken by its truth value (None means go on); anything raised is kept, the work is
/// told to stop, and rethrow() raises it after the work has returned.
class PyStopCheck {
public:
    explicit PyStopCheck(nb::object progress = nb::none()) : progress_(std::move(progress)) {}

    /// True to stop. `fraction` is passed to the progress callable. While the interpreter
    /// finishes, the thread parks instead (park_if_finishing).
    bool operator()(double fraction) {
        park_if_finishing();
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

    PyLongCall counted_;
    nb::object progress_;
    std::optional<nb::python_error> error_;
};

}  // namespace bvhlab::python
