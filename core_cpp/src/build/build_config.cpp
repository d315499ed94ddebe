#include "bvhlab/build_config.h"

#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "../platform/number_text.h"
#include "bvhlab/split.h"

namespace bvhlab {
namespace {

constexpr std::array<std::pair<std::string_view, AxisPolicy>, 4> kAxes{{
    {"auto", AxisPolicy::Auto},
    {"largest", AxisPolicy::Largest},
    {"random", AxisPolicy::Random},
    {"best", AxisPolicy::Best},
}};

constexpr std::array<std::pair<std::string_view, BinBounds>, 2> kBinBounds{{
    {"centroids", BinBounds::Centroids},
    {"box", BinBounds::Box},
}};

[[noreturn]] void throw_unknown(const char* what, std::string_view name, const std::vector<std::string_view>& names) {
    // (appends rather than operator+ chains: GCC 12 warns falsely on those, bug 105329)
    std::string msg = "unknown ";
    msg.append(what).append(" '").append(name).append("'; expected one of:");
    for (std::string_view n : names) msg.append(" ").append(n);
    throw std::invalid_argument(msg);
}

}  // namespace

std::vector<std::string_view> split_method_names() {
    std::vector<std::string_view> names;
    for (const SplitMethodInfo& m : split_methods()) names.push_back(m.name);
    return names;
}

std::vector<std::string_view> axis_policy_names() {
    std::vector<std::string_view> names;
    for (const auto& entry : kAxes) names.push_back(entry.first);
    return names;
}

std::vector<std::string_view> bin_bounds_names() {
    std::vector<std::string_view> names;
    for (const auto& entry : kBinBounds) names.push_back(entry.first);
    return names;
}

SplitMethod parse_split_method(std::string_view name) {
    for (const SplitMethodInfo& m : split_methods())
        if (m.name == name) return m.method;
    throw_unknown("split method", name, split_method_names());
}

AxisPolicy parse_axis_policy(std::string_view name) {
    for (const auto& [key, value] : kAxes)
        if (key == name) return value;
    throw_unknown("axis policy", name, axis_policy_names());
}

BinBounds parse_bin_bounds(std::string_view name) {
    for (const auto& [key, value] : kBinBounds)
        if (key == name) return value;
    throw_unknown("bin bounds", name, bin_bounds_names());
}

std::string to_string(SplitMethod method) { return std::string(method_info(method).name); }

std::string to_string(AxisPolicy axis) {
    for (const auto& [key, value] : kAxes)
        if (value == axis) return std::string(key);
    return "?";
}

std::string to_string(BinBounds bounds) {
    for (const auto& [key, value] : kBinBounds)
        if (value == bounds) return std::string(key);
    return "?";
}

bool uses_sah(SplitMethod m) { return method_info(m).uses_sah; }

void validate(const BuildConfig& config) {
    if (config.bins < kMinBins || config.bins > kMaxBins)
        throw std::invalid_argument("bins must be between " + std::to_string(kMinBins) + " and " +
                                    std::to_string(kMaxBins) + ", got " + std::to_string(config.bins));
    if (config.max_leaf_size < 1 || config.max_leaf_size > kMaxLeafSize)
        throw std::invalid_argument("max_leaf_size must be between 1 and " + std::to_string(kMaxLeafSize) + ", got " +
                                    std::to_string(config.max_leaf_size));
    const std::uint32_t block = config.sah_block;
    if (block < 1 || block > kMaxSahBlock || (block & (block - 1)))
        throw std::invalid_argument("sah_block must be a power of two from 1 to " + std::to_string(kMaxSahBlock) +
                                    ", got " + std::to_string(block));
    if (!std::isfinite(config.traversal_cost) || !std::isfinite(config.intersection_cost) ||
        config.traversal_cost < 0.0f || config.intersection_cost <= 0.0f)
        throw std::invalid_argument("SAH costs must be finite, traversal >= 0 and intersection > 0");
    if (!(config.sbvh_alpha >= 0.0f) || !std::isfinite(config.sbvh_alpha))
        throw std::invalid_argument("sbvh_alpha must be a finite number >= 0, got " + number_text(config.sbvh_alpha));
    if (!(config.sbvh_budget >= 1.0f) || !(config.sbvh_budget <= 64.0f))
        throw std::invalid_argument("sbvh_budget must be a number from 1 to 64 (references per primitive), got " +
                                    number_text(config.sbvh_budget));
}

}  // namespace bvhlab
