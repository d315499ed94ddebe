// sah.h — the surface area heuristic of a split, defined once (report §2.3.2, eq. 1; PBRT §4.3.2;
// madmann91/bvh's SplitHeuristic is the model). Every split method that weighs splits uses it.
#pragma once
#include <cstdint>

#include "bvhlab/build_config.h"

namespace bvhlab {

/// Expected cost of a node (report eq. 1 plus PBRT's leaf term): a split costs
/// C_trav + (A_L·N_L + A_R·N_R) / A_P · C_isect, a leaf N · C_isect. Areas are half areas (only
/// ratios matter). A parent of zero area (primitives on a line or a point) gives no probabilities;
/// every primitive counts as hit then, so a split never looks cheaper than it is.
struct SahCost {
    float traversal = 1.0f, intersection = 1.0f;

    SahCost() = default;
    explicit SahCost(const BuildConfig& c) : traversal(c.traversal_cost), intersection(c.intersection_cost) {}

    /// 1 / A_P, or 0 for a parent of zero area: pass it to split().
    static float inverse_area(float parent_area) { return parent_area > 0.0f ? 1.0f / parent_area : 0.0f; }

    float split(float inv_parent_area, float left_area, std::uint32_t n_left, float right_area,
                std::uint32_t n_right) const {
        const float ratio = inv_parent_area > 0.0f
                                ? (left_area * float(n_left) + right_area * float(n_right)) * inv_parent_area
                                : float(n_left + n_right);
        return traversal + ratio * intersection;
    }
    float leaf(std::uint32_t n) const { return float(n) * intersection; }
};

}  // namespace bvhlab
