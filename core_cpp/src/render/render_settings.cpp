// The render settings' checks (one place for every limit) and the names of their choices.
#include "bvhlab/render_settings.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "../platform/number_text.h"
#include "gpu_types.h"

namespace bvhlab {
namespace {

constexpr std::array<std::pair<std::string_view, Traversal>, 3> kTraversals{
    {{"stack", Traversal::Stack}, {"stackless", Traversal::Stackless}, {"wide", Traversal::Wide}}};
constexpr std::array<std::pair<std::string_view, RenderMode>, 2> kModes{
    {{"shade", RenderMode::Shade}, {"heatmap", RenderMode::Heatmap}}};
constexpr std::array<std::pair<std::string_view, TraversalCounter>, gpu::COUNTER_COUNT> kCounters{
    {{"box_tests", TraversalCounter::BoxTests},
     {"box_hits", TraversalCounter::BoxHits},
     {"prim_tests", TraversalCounter::PrimTests},
     {"prim_hits", TraversalCounter::PrimHits},
     {"instance_hits", TraversalCounter::InstanceHits}}};
static_assert(std::uint32_t(TraversalCounter::BoxTests) == gpu::COUNTER_BOX_TESTS &&
              std::uint32_t(TraversalCounter::BoxHits) == gpu::COUNTER_BOX_HITS &&
              std::uint32_t(TraversalCounter::PrimTests) == gpu::COUNTER_PRIM_TESTS &&
              std::uint32_t(TraversalCounter::PrimHits) == gpu::COUNTER_PRIM_HITS &&
              std::uint32_t(TraversalCounter::InstanceHits) == gpu::COUNTER_INSTANCE_HITS);

template <class Table>
auto lookup(const Table& table, std::string_view name, const char* what) {
    std::string names;
    for (const auto& [key, value] : table) {
        if (key == name) return value;
        names.append(" ").append(key);
    }
    std::string msg = "unknown ";
    msg.append(what).append(" '").append(name).append("'; expected one of:").append(names);
    throw std::invalid_argument(msg);
}

template <class Table, class Value>
std::string name_in(const Table& table, Value value) {
    for (const auto& [key, v] : table)
        if (v == value) return std::string(key);
    return "?";
}

[[noreturn]] void fail(const std::string& msg) { throw std::invalid_argument(msg); }

void validate_light(const RenderSettings& s) {
    if (!all_finite(s.light.position) || !all_finite(s.light.color) || !std::isfinite(s.light.intensity))
        fail("the light has a NaN or infinite value");
    if (!all_finite(s.sky)) fail("the sky colour has a NaN or infinite value");
}

void validate_work(const RenderSettings& s) {
    if (s.samples_per_axis < 1 || s.samples_per_axis > gpu::MAX_SAMPLES_PER_AXIS)
        fail("samples_per_axis (samples per pixel axis) must be 1.." + std::to_string(gpu::MAX_SAMPLES_PER_AXIS));
    if (s.max_ray_depth > gpu::MAX_RAY_DEPTH)
        fail("max_ray_depth must be at most " + std::to_string(gpu::MAX_RAY_DEPTH));
    if (s.traversal == Traversal::Wide && s.traversal_counters)
        fail(
            "traversal counters need the 'stack' or 'stackless' traversal; 'wide' keeps only the heatmap "
            "mode's cost (8 box tests a wide node visited)");
    if (s.mode == RenderMode::Heatmap && !s.keep_cost)
        fail("the heatmap mode shows each pixel's cost: it needs keep_cost");
    if (s.steps_per_dispatch &&
        (*s.steps_per_dispatch < gpu::MIN_STEPS_PER_DISPATCH || *s.steps_per_dispatch > gpu::MAX_STEPS_PER_DISPATCH))
        fail("steps_per_dispatch must be " + std::to_string(gpu::MIN_STEPS_PER_DISPATCH) + ".." +
             std::to_string(gpu::MAX_STEPS_PER_DISPATCH));
    if (s.max_steps_per_pixel && *s.max_steps_per_pixel < 1) fail("max_steps_per_pixel must be at least 1");
}

void validate_look(const RenderSettings& s) {
    if (s.heatmap_scale &&
        !(std::isfinite(*s.heatmap_scale) && *s.heatmap_scale > 0 && *s.heatmap_scale <= kMaxHeatmapScale))
        fail("heatmap_scale must be a positive number of box tests up to " + std::to_string(int(kMaxHeatmapScale)) +
             ", got " + number_text(*s.heatmap_scale));
    if (!(s.line_width >= 1.0f && s.line_width <= kMaxLineWidth)) fail("line_width must be in [1, 16]");
    if (s.overlay && s.overlay_depth_min > s.overlay_depth_max)
        fail("overlay depth_min " + std::to_string(s.overlay_depth_min) + " is greater than depth_max " +
             std::to_string(s.overlay_depth_max));
}

}  // namespace

void validate_image_size(std::uint32_t width, std::uint32_t height, std::uint32_t max_dimension) {
    if (width == 0 || height == 0)
        fail("width and height must be at least 1, got " + std::to_string(width) + "x" + std::to_string(height));
    if (width > max_dimension || height > max_dimension)
        fail("image size " + std::to_string(width) + "x" + std::to_string(height) + " exceeds the device limit of " +
             std::to_string(max_dimension) + " pixels per side");
}

void validate(const RenderSettings& s, std::uint32_t max_dimension) {
    validate_image_size(s.width, s.height, max_dimension);
    validate(s.camera);
    if (s.overlay && s.camera.panoramic())
        fail("the box overlay draws straight lines: it needs a perspective or orthographic camera, not " +
             to_string(s.camera.projection));
    validate_light(s);
    validate_work(s);
    validate_look(s);
}

Traversal parse_traversal(std::string_view name) { return lookup(kTraversals, name, "traversal"); }
RenderMode parse_render_mode(std::string_view name) { return lookup(kModes, name, "mode"); }
std::string to_string(Traversal traversal) { return name_in(kTraversals, traversal); }
std::string to_string(RenderMode mode) { return name_in(kModes, mode); }
TraversalCounter parse_traversal_counter(std::string_view name) { return lookup(kCounters, name, "counter"); }
std::string to_string(TraversalCounter counter) { return name_in(kCounters, counter); }
std::vector<std::string> traversal_counter_names() {
    std::vector<std::string> out;
    for (const auto& entry : kCounters) out.emplace_back(entry.first);
    return out;
}

std::vector<std::string> traversal_names() {
    std::vector<std::string> out;
    for (const auto& entry : kTraversals) out.emplace_back(entry.first);
    return out;
}
std::vector<std::string> render_mode_names() {
    std::vector<std::string> out;
    for (const auto& entry : kModes) out.emplace_back(entry.first);
    return out;
}

std::uint32_t gpu_traversal(Traversal traversal) {
    if (traversal == Traversal::Wide) return gpu::TRAVERSAL_WIDE;
    return traversal == Traversal::Stackless ? gpu::TRAVERSAL_STACKLESS : gpu::TRAVERSAL_STACK;
}

}  // namespace bvhlab
