// optimize_bindings.cpp — optimisation of a Python Bvh after its build (optimize.h): the
// OptimizeConfig and `_core.optimize_bvh`, which publishes the optimised tree as a new version of
// the Bvh (py_bvh.h) and returns what the optimisation did.
#include <algorithm>
#include <chrono>

#include <nanobind/nanobind.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>

#include "bvhlab/optimize.h"
#include "py_bvh.h"
#include "py_cancel.h"

namespace nb = nanobind;
using namespace nb::literals;
using namespace bvhlab;
using namespace bvhlab::python;

namespace {

nb::dict optimize(PyBvh& self, const OptimizeConfig& config, std::optional<nb::callable> progress) {
    validate(config);
    // the TLAS copy of a two-level tree is a view of it, made once and handed out again: optimised,
    // every later InstancedBvh.tlas was another tree than the one its queries and stats walk
    require_geometry(self.current()->bvh, "optimize");
    // Ctrl-C or a false progress stops it (BuildCancelled), the tree as it was
    PyStopCheck stop(progress ? nb::object(*progress) : nb::none());
    OptimizeStats stats;
    try {
        const LongRelease release;
        // the fraction reported is of the iteration bound, or of the time budget where that is
        // further (a bar of iterations stood at 3% when 300 ms ran out); a run that converges ends
        // earlier (Bvh.optimize reports 1 once done)
        const auto start = std::chrono::steady_clock::now();
        Cancellation cancel([&stop, &stats, &config, start] {
            double fraction = config.iterations ? double(stats.iterations) / config.iterations : 1.0;
            if (config.time_budget_ms > 0) {
                const std::chrono::duration<double, std::milli> ran = std::chrono::steady_clock::now() - start;
                fraction = std::max(fraction, ran.count() / config.time_budget_ms);
            }
            return stop(std::min(fraction, 1.0));
        });
        self.replace([&](const TreeVersion& old) {
            Bvh out = optimized(old.bvh, config, &cancel, &stats);
            // done: 1 reported before the tree is published, under the same rules (a false answer
            // or Ctrl-C still leaves the tree as it was; a change from the callable is refused)
            if (stop(1.0)) throw Cancelled();
            // the optimised tree is a tree as built: its costs are its own (null: taken on first need)
            return std::pair{std::move(out), CostsPtr()};
        });
    } catch (const Cancelled&) {
        stop.rethrow();  // what the callable (or Ctrl-C) raised, as itself
        throw BuildCancelled();
    }
    nb::dict d;
    d["sah_before"] = stats.sah_before, d["sah_after"] = stats.sah_after;
    d["iterations"] = stats.iterations, d["attempts"] = stats.attempts, d["reinsertions"] = stats.reinsertions;
    d["leaves_merged"] = stats.leaves_merged, d["ms"] = stats.ms, d["stop"] = to_string(stats.stop);
    return d;
}

}  // namespace

void bind_optimize(nb::module_& m) {
    nb::class_<OptimizeConfig>(m, "OptimizeConfig",
                               "How a built tree is optimised by reinsertion (optimize.h), defaults included.")
        .def(nb::init<>())
        .def_rw("iterations", &OptimizeConfig::iterations)
        .def_rw("time_budget_ms", &OptimizeConfig::time_budget_ms)
        .def_rw("batch_fraction", &OptimizeConfig::batch_fraction)
        .def_rw("merge_leaves", &OptimizeConfig::merge_leaves)
        .def(
            "validate", [](const OptimizeConfig& self) { validate(self); },
            "Raises ValueError naming the first setting out of range.");
    m.def("optimize_bvh", &optimize, "bvh"_a, "config"_a, "progress"_a.none(),
          "Optimises the tree by reinsertion (Bittner et al. 2013) as a new version; returns what it did.");
}
