#include "bvhlab/stats.h"

#include <algorithm>

namespace bvhlab {

double sah_cost(const Bvh& bvh) {
    if (bvh.empty()) return 0.0;
    const double root_area = node_half_area(bvh.nodes[0]);
    double cost = 0.0;
    for (const BvhNode& n : bvh.nodes) cost += sah_term(n, root_area);
    return cost;
}

BvhStats compute_stats(const Bvh& bvh) {
    BvhStats s;
    s.triangles = bvh.triangle_count;
    s.spheres = bvh.sphere_count;
    s.primitives = s.triangles + s.spheres;
    s.references = bvh.refs.size();
    s.nodes = bvh.nodes.size();
    s.build_ms = bvh.build_ms;
    // one pass: sah_cost's terms summed in its order (the same bits), the counts beside them
    const double root_area = bvh.empty() ? 0.0 : node_half_area(bvh.nodes[0]);
    for (std::size_t i = 0; i < bvh.nodes.size(); ++i) {
        const BvhNode& n = bvh.nodes[i];
        s.sah_cost += sah_term(n, root_area);
        std::uint32_t d = bvh.depths[i];
        if (s.nodes_per_depth.size() <= d) s.nodes_per_depth.resize(d + 1), s.leaves_per_depth.resize(d + 1);
        ++s.nodes_per_depth[d];
        if (!is_leaf(n)) continue;
        ++s.leaves;
        ++s.leaves_per_depth[d];
        s.height = std::max(s.height, d + 1);
        std::uint32_t count = leaf_count(n);
        s.max_leaf_size = std::max(s.max_leaf_size, count);
        if (s.leaf_size_histogram.size() <= count) s.leaf_size_histogram.resize(count + 1);
        ++s.leaf_size_histogram[count];
    }
    s.avg_leaf_size = s.leaves ? double(bvh.refs.size()) / double(s.leaves) : 0.0;
    s.memory_bytes = bvh.nodes.size() * sizeof(BvhNode) + bvh.refs.size() * sizeof(std::uint32_t) + bvh.depths.size() +
                     bvh.prims.size() * sizeof(PackedPrim);
    return s;
}

}  // namespace bvhlab
