// The one table of split methods: the config parser, the builder, the stats' names and the
// Python module all read it (adding a method is one row here and one split_*.cpp file).
#include <array>
#include <stdexcept>

#include "bvhlab/split.h"

namespace bvhlab {
namespace {

//     method                name         function          all axes  SAH    sum    Morton bottom-up binned
constexpr std::array<SplitMethodInfo, 7> kMethods{{
    {SplitMethod::Median, "median", split_median, false, false, false, false, false, false},
    {SplitMethod::Mean, "mean", split_mean, false, false, true, false, false, false},
    {SplitMethod::Midpoint, "midpoint", split_midpoint, false, false, false, false, false, false},
    {SplitMethod::Sah, "sah", split_binned_sah, true, true, false, false, false, true},
    {SplitMethod::SweepSah, "sweep_sah", split_sweep_sah, true, true, false, false, false, false},
    {SplitMethod::Lbvh, "lbvh", split_lbvh, true, false, false, true, true, false},
    // its own builder (sbvh/sbvh_builder.h), which build_bvh calls instead of the split function's:
    // binned SAH object splits and binned spatial splits
    {SplitMethod::Sbvh, "sbvh", split_binned_sah, true, true, false, false, false, true},
}};

}  // namespace

std::span<const SplitMethodInfo> split_methods() { return kMethods; }

const SplitMethodInfo& method_info(SplitMethod method) {
    const auto i = static_cast<std::size_t>(method);
    if (i >= kMethods.size()) throw std::invalid_argument("unknown split method");
    return kMethods[i];  // rows in the order of the enum (checked below)
}

static_assert([] {
    for (std::size_t i = 0; i < kMethods.size(); ++i)
        if (static_cast<std::size_t>(kMethods[i].method) != i) return false;
    return true;
}());

// The binned methods are those whose splits are the binned SAH's (the only reader of config.bins
// but the SBVH builder, whose row names it too): tests/cpp/test_split_methods.cpp checks it (a
// static_assert comparing function addresses is no constant expression under GCC's sanitizers).

}  // namespace bvhlab
