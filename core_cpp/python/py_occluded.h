// py_occluded.h — what Bvh.occluded and TwoLevel.occluded share: the rays (tmax a scalar or one
// per ray) and the run with the GIL released and Ctrl-C honoured.
#pragma once
#include <optional>
#include <stdexcept>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>

#include "bvhlab/cancel.h"
#include "bvhlab/traverse.h"
#include "py_cancel.h"

namespace bvhlab::python {

using RayVectors = nb::ndarray<const float, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using RayFloats = nb::ndarray<const float, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Occluded = nb::ndarray<bool, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

/// The batch of an occluded call, its lengths checked: `tmax_of` (one per ray) replaces `tmax`.
inline RayBatch occluded_rays(const RayVectors& origins, const RayVectors& dirs, float tmin, float tmax,
                              const std::optional<RayFloats>& tmax_of, const Occluded& out) {
    const std::size_t n = origins.shape(0);
    if (dirs.shape(0) != n) throw std::invalid_argument("origins and directions differ in length");
    if (tmax_of && tmax_of->shape(0) != n) throw std::invalid_argument("tmax must be a number or one per ray");
    if (out.shape(0) != n) throw std::invalid_argument("output arrays must have one entry per ray");
    return RayBatch{origins.data(), dirs.data(), n, tmin, tmax, tmax_of ? tmax_of->data() : nullptr};
}

/// run(cancel) with the GIL released; Ctrl-C stops it (KeyboardInterrupt).
template <class Run>
void run_released(Run&& run) {
    PyStopCheck stop;
    Cancellation cancel([&stop] { return stop(0.0); });
    try {
        const LongRelease release;
        run(&cancel);
    } catch (const Cancelled&) {
        stop.rethrow();
        throw;
    }
}

}  // namespace bvhlab::python
