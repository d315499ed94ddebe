// depth_order.h — node indices sorted by depth, so a depth range is one offset and one count
// (report §3.3.1: the overlay draws a range of depths with a single instanced draw).
#pragma once
#include <cstdint>
#include <vector>
#include "bvhlab/bvh.h"

namespace bvhlab {

struct DepthOrder {
    std::vector<std::uint32_t> nodes;   ///< node indices, by depth, depth-first order within a depth
    std::vector<std::uint32_t> offset;  ///< nodes of depth d are nodes[offset[d], offset[d + 1])

    /// [first, last) positions in `nodes` of the depths d with depth_min <= d <= depth_max (the one
    /// convention for depth ranges: the overlay pass, Bvh.boxes and the add-on all use it).
    std::pair<std::uint32_t, std::uint32_t> range(std::uint32_t depth_min, std::uint32_t depth_max) const;
    /// Levels of the tree: the largest leaf depth + 1 (0 for an empty tree).
    std::uint32_t height() const { return offset.empty() ? 0 : static_cast<std::uint32_t>(offset.size() - 1); }
};

DepthOrder make_depth_order(const Bvh& bvh);

}  // namespace bvhlab
