// update_bindings.cpp — updates of a Python Bvh over deforming geometry (update.h): the
// UpdateConfig and `_core.update_bvh`, which publishes the updated tree as a new version of the
// Bvh (py_bvh.h) and returns what the update did.
#include <nanobind/nanobind.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>

#include "bvhlab/update.h"
#include "py_bvh.h"
#include "py_cancel.h"

namespace nb = nanobind;
using namespace nb::literals;
using namespace bvhlab;
using namespace bvhlab::python;

namespace {

nb::dict update(PyBvh& self, const Triangles& tris, const std::optional<Spheres>& spheres, const UpdateConfig& config) {
    validate(config);
    require_geometry(self.current()->bvh, "update");
    // without spheres the rebuild policy built the triangles alone: the tree's spheres were gone
    if (const std::uint32_t had = self.current()->bvh.sphere_count; !spheres && had)
        throw std::invalid_argument("the tree has " + std::to_string(had) +
                                    " spheres: pass them (or an empty (0, 4) array to remove them)");
    const GeometryView g = view_of(tris, spheres);
    UpdateStats stats;
    // Ctrl-C stops a rebuild (its progress) and, wherever it came, keeps the tree as it was: it is
    // looked for once more before the new version is published (it was raised after the update,
    // the tree changed and its stats lost: a helper's audit)
    PyStopCheck stop;
    UpdateConfig cfg = config;
    cfg.progress = [&stop](double done) { return !stop(done); };
    try {
        const LongRelease release;
        self.replace([&](const TreeVersion& old) {
            auto built = std::make_shared<NodeCostArray>();
            Bvh tree = update_bvh(old.bvh, *old.built_costs(), g, cfg, *built, &stats);
            if (stop(1.0)) throw BuildCancelled();
            return std::pair{std::move(tree), CostsPtr(std::move(built))};
        });
    } catch (const BuildCancelled&) {
        stop.rethrow();  // the KeyboardInterrupt, as itself
        throw;
    }
    nb::dict d;
    d["policy"] = to_string(stats.policy), d["ms"] = stats.ms, d["sah_cost"] = stats.sah_cost;
    d["subtrees_rebuilt"] = stats.subtrees_rebuilt, d["primitives_rebuilt"] = stats.primitives_rebuilt;
    d["top_boxes"] = stats.top_boxes;
    d["fresh_sah_cost"] = stats.fresh_sah_cost < 0 ? nb::none() : nb::cast(stats.fresh_sah_cost);
    return d;
}

}  // namespace

void bind_update(nb::module_& m) {
    nb::class_<UpdateConfig> c(m, "UpdateConfig",
                               "How a tree is updated for moved geometry (update.h), defaults included.");
    c.def(nb::init<>())
        .def_prop_rw(
            "policy", [](const UpdateConfig& self) { return to_string(self.policy); },
            [](UpdateConfig& self, const std::string& name) { self.policy = parse_update_policy(name); },
            "rebuild, refit, partial or adaptive")
        .def_rw("subtree_growth", &UpdateConfig::subtree_growth)
        .def_rw("tree_growth", &UpdateConfig::tree_growth)
        .def_rw("target_growth", &UpdateConfig::target_growth)
        .def_rw("restructure_share", &UpdateConfig::restructure_share)
        .def_rw("min_subtree_primitives", &UpdateConfig::min_subtree_primitives)
        .def_rw("top_cut_primitives", &UpdateConfig::top_cut_primitives)
        .def_rw("top_growth", &UpdateConfig::top_growth)
        .def_rw("top_intact_primitives", &UpdateConfig::top_intact_primitives)
        .def_rw("top_coarse_cut_primitives", &UpdateConfig::top_coarse_cut_primitives)
        .def_rw("measure_fresh", &UpdateConfig::measure_fresh)
        .def(
            "validate", [](const UpdateConfig& self) { validate(self); },
            "Raises ValueError naming the first setting out of range.");
    nb::list names;
    for (std::string_view name : update_policy_names()) names.append(std::string(name));
    m.attr("UPDATE_POLICIES") = nb::tuple(names);
    m.def("update_bvh", &update, "bvh"_a, "triangles"_a.noconvert(), "spheres"_a.noconvert().none(), "config"_a,
          "Updates the tree for moved geometry (same counts) by config.policy; returns what ran (policy, ms, "
          "sah_cost, subtrees_rebuilt, primitives_rebuilt).");
}
