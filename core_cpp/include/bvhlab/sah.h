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
///
/// Counts are in blocks (`block`, a power of two; BuildConfig::sah_block): below a node of more
/// than one block, each count N is rounded up to whole blocks, as a traversal that tests a block
/// of primitives at once pays for them (Embree's sahBlockSize; bvhlab's wide CPU traversal tests
/// four triangles at once, wide_bvh.h). A node of one block or less is held in one block whatever
/// its split, so its own split and leaf costs count primitives (the report's SAH; the binary
/// traversals test them one by one). block = 1 is the report's SAH everywhere.
struct SahCost {
    float traversal = 1.0f, intersection = 1.0f;
    std::uint32_t block = 1;

    SahCost() = default;
    explicit SahCost(const BuildConfig& c)
        : traversal(c.traversal_cost), intersection(c.intersection_cost), block(c.sah_block) {}

    /// What rounds the counts under a node of `n` primitives: block - 1 when n > block, else 0.
    std::uint32_t round_mask(std::uint64_t n) const { return n > block ? block - 1 : 0; }
    /// `n` as the SAH counts it under the mask of round_mask (below 2^31, and so is the sum of a
    /// node's two: a build takes at most 2^31 - 1 - 2 (kMaxSahBlock - 1) primitives, geometry.cpp).
    static std::uint32_t counted(std::uint32_t n, std::uint32_t mask) { return (n + mask) & ~mask; }
    /// 1 / A_P, or 0 for a parent of zero area: pass it to split().
    static float inverse_area(float parent_area) { return parent_area > 0.0f ? 1.0f / parent_area : 0.0f; }

    float split(float inv_parent_area, float left_area, std::uint32_t n_left, float right_area,
                std::uint32_t n_right) const {
        const std::uint32_t mask = round_mask(std::uint64_t(n_left) + n_right);
        n_left = counted(n_left, mask), n_right = counted(n_right, mask);
        const float ratio = inv_parent_area > 0.0f
                                ? (left_area * float(n_left) + right_area * float(n_right)) * inv_parent_area
                                : float(n_left + n_right);
        return traversal + ratio * intersection;
    }
    float leaf(std::uint32_t n) const { return float(counted(n, round_mask(n))) * intersection; }
};

}  // namespace bvhlab
