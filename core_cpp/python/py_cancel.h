// py_cancel.h — long work started from Python stops on Ctrl-C and when a progress callable says so,
// and what Python raised is raised again, as itself, once every worker thread has stopped.
#pragma once
#include <optional>
#include <utility>

#include <nanobind/nanobind.h>

#include "bvhlab/cancel.h"

namespace bvhlab::python {

namespace nb = nanobind;

/// The check of a Cancellation (cancel.h) for work started from Python. Runs on the calling
/// thread, with the GIL released around it: it takes the GIL, runs Python's signal handlers
/// (Ctrl-C raises KeyboardInterrupt there) and then the progress callable, if any. The callable's
/// result is taken by its truth value (None means go on); anything raised is kept, the work is
/// told to stop, and rethrow() raises it after the work has returned.
class PyStopCheck {
public:
    explicit PyStopCheck(nb::object progress = nb::none()) : progress_(std::move(progress)) {}

    /// True to stop. `fraction` is passed to the progress callable.
    bool operator()(double fraction) {
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
