// Binding of BuildConfig (build_config.h): the one typed object a build is asked for, from
// Python's bvhlab.BuildConfig, the CLI and the add-on alike. Its defaults are the C++ ones; its
// names are the method table's (split_methods.cpp); its values are checked once, by validate().
#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>

#include "bvhlab/build_config.h"

namespace nb = nanobind;
using namespace bvhlab;

namespace {

/// An enum member as a read-write property spelled by name (parse_* refuse unknown names).
template <class Enum, Enum BuildConfig::* Member, Enum (*Parse)(std::string_view)>
void name_property(nb::class_<BuildConfig>& c, const char* name, const char* doc) {
    c.def_prop_rw(
        name, [](const BuildConfig& self) { return to_string(self.*Member); },
        [](BuildConfig& self, const std::string& value) { self.*Member = Parse(value); }, doc);
}

}  // namespace

void bind_build_config(nb::module_& m) {
    nb::class_<BuildConfig> c(m, "BuildConfig", "What a build is asked to do (build_config.h), defaults included.");
    c.def(nb::init<>());
    name_property<SplitMethod, &BuildConfig::method, parse_split_method>(c, "method", "split method name");
    name_property<AxisPolicy, &BuildConfig::axis, parse_axis_policy>(c, "axis", "axis policy name");
    name_property<BinBounds, &BuildConfig::bin_bounds, parse_bin_bounds>(c, "bin_bounds",
                                                                         "what the binned SAH's buckets divide");
    c.def_rw("bins", &BuildConfig::bins)
        .def_rw("max_leaf_size", &BuildConfig::max_leaf_size)
        .def_rw("sah_block", &BuildConfig::sah_block)
        .def_rw("seed", &BuildConfig::seed)
        .def_rw("sbvh_alpha", &BuildConfig::sbvh_alpha,
                "sbvh: overlap (fraction of the root's area) above which spatial splits are tried")
        .def_rw("sbvh_budget", &BuildConfig::sbvh_budget, "sbvh: at most this many references per primitive")
        .def_rw("sbvh_unsplit", &BuildConfig::sbvh_unsplit, "sbvh: reference unsplitting")
        .def_rw("threads", &BuildConfig::threads, "0: every hardware thread; the tree never depends on it")
        .def(
            "validate", [](const BuildConfig& self) { validate(self); },
            "Raises ValueError naming the first setting out of range.");
    m.attr("MIN_BINS") = kMinBins;
    m.attr("MAX_BINS") = kMaxBins;
    m.attr("MAX_LEAF_SIZE") = kMaxLeafSize;
    m.attr("MAX_SAH_BLOCK") = kMaxSahBlock;
    m.def("sbvh_reference_limit", &sbvh_reference_limit, nb::arg("primitives"), nb::arg("config"),
          "The most references an SBVH over that many primitives may hold.");
}
