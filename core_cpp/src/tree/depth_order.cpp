#include "bvhlab/depth_order.h"

#include <algorithm>

namespace bvhlab {

DepthOrder make_depth_order(const Bvh& bvh) {
    DepthOrder order;
    std::uint32_t levels = 0;
    for (std::uint8_t d : bvh.depths) levels = std::max<std::uint32_t>(levels, d + 1u);
    order.offset.assign(levels + 1, 0);
    for (std::uint8_t d : bvh.depths) ++order.offset[d + 1];
    for (std::uint32_t d = 0; d < levels; ++d) order.offset[d + 1] += order.offset[d];
    order.nodes.resize(bvh.depths.size());
    std::vector<std::uint32_t> cursor(order.offset.begin(), order.offset.end() - 1);
    for (std::uint32_t i = 0; i < bvh.depths.size(); ++i) order.nodes[cursor[bvh.depths[i]]++] = i;
    return order;
}

std::pair<std::uint32_t, std::uint32_t> DepthOrder::range(std::uint32_t depth_min, std::uint32_t depth_max) const {
    const std::uint32_t levels = height();
    if (depth_min > depth_max || depth_min >= levels) return {0, 0};  // also: no levels at all
    depth_max = std::min(depth_max, levels - 1);
    return {offset[depth_min], offset[depth_max + 1]};
}

}  // namespace bvhlab
