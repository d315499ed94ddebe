#include "bvhlab/build_config.h"

#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace bvhlab {
namespace {

constexpr std::array<std::pair<std::string_view, SplitMethod>, 6> kMethods{{
    {"median", SplitMethod::Median},
    {"mean", SplitMethod::Mean},
    {"midpoint", SplitMethod::Midpoint},
    {"sah", SplitMethod::Sah},
    {"sweep_sah", SplitMethod::SweepSah},
    {"lbvh", SplitMethod::Lbvh},
}};
constexpr std::array<std::pair<std::string_view, AxisPolicy>, 3> kAxes{{
    {"largest", AxisPolicy::Largest},
    {"random", AxisPolicy::Random},
    {"best", AxisPolicy::Best},
}};

template <class Table>
auto parse(const Table& table, std::string_view name, const char* what) {
    for (const auto& [key, value] : table)
        if (key == name) return value;
    // (appends rather than operator+ chains: GCC 12 warns falsely on those, bug 105329)
    std::string msg = "unknown ";
    msg.append(what).append(" '").append(name).append("'; expected one of:");
    for (const auto& entry : table) msg.append(" ").append(entry.first);
    throw std::invalid_argument(msg);
}

template <class Table, class Value>
std::string name_of(const Table& table, Value value) {
    for (const auto& [key, v] : table)
        if (v == value) return std::string(key);
    return "?";
}

}  // namespace

SplitMethod parse_split_method(std::string_view name) { return parse(kMethods, name, "split method"); }
AxisPolicy parse_axis_policy(std::string_view name) { return parse(kAxes, name, "axis policy"); }
std::string to_string(SplitMethod method) { return name_of(kMethods, method); }
std::string to_string(AxisPolicy axis) { return name_of(kAxes, axis); }

void validate(const BuildConfig& config) {
    if (config.bins < kMinBins || config.bins > kMaxBins)
        throw std::invalid_argument("bins must be between 2 and 256, got " + std::to_string(config.bins));
    if (config.max_leaf_size < 1)
        throw std::invalid_argument("max_leaf_size must be at least 1");
    if (!std::isfinite(config.traversal_cost) || !std::isfinite(config.intersection_cost) ||
        config.traversal_cost < 0.0f || config.intersection_cost <= 0.0f)
        throw std::invalid_argument("SAH costs must be finite, traversal >= 0 and intersection > 0");
}

}  // namespace bvhlab
