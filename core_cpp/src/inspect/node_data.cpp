// node_data.cpp — every node's data in one pass down and one pass up the depth-first nodes.
#include "bvhlab/node_data.h"

#include <algorithm>
#include <limits>

#include "bvhlab/stats.h"

namespace bvhlab {

namespace {

/// Half area of the intersection of two nodes' boxes (0 when they are apart).
double overlap_half_area(const BvhNode& a, const BvhNode& b) {
    const double x = std::min(double(a.hi.x), double(b.hi.x)) - std::max(double(a.lo.x), double(b.lo.x));
    const double y = std::min(double(a.hi.y), double(b.hi.y)) - std::max(double(a.lo.y), double(b.lo.y));
    const double z = std::min(double(a.hi.z), double(b.hi.z)) - std::max(double(a.lo.z), double(b.lo.z));
    if (x < 0 || y < 0 || z < 0) return 0.0;
    return x * y + y * z + z * x;
}

void resize_all(NodeData& d, std::size_t n) {
    d.lo.resize(3 * n), d.hi.resize(3 * n), d.depth.resize(n), d.parent.assign(n, -1);
    d.left.assign(n, -1), d.right.assign(n, -1), d.prim_count.assign(n, 0);
    d.area.resize(n), d.sah_term.resize(n), d.subtree_sah.resize(n), d.sah_share.resize(n);
    d.child_overlap.assign(n, 0.0);
}

}  // namespace

NodeData compute_node_data(const Bvh& bvh, unsigned threads, Cancellation* cancel, bool epo) {
    NodeData d;
    const std::uint32_t n = bvh.node_count();
    resize_all(d, n);
    if (n == 0) return d;
    const double root_half_area = node_half_area(bvh.nodes[0]);
    // Down: what a node is on its own, and its children's parent.
    for (std::uint32_t i = 0; i < n; ++i) {
        const BvhNode& node = bvh.nodes[i];
        d.lo[3 * i] = node.lo.x, d.lo[3 * i + 1] = node.lo.y, d.lo[3 * i + 2] = node.lo.z;
        d.hi[3 * i] = node.hi.x, d.hi[3 * i + 1] = node.hi.y, d.hi[3 * i + 2] = node.hi.z;
        d.depth[i] = bvh.depths[i];
        const double half = node_half_area(node);
        d.area[i] = 2.0 * half;
        d.sah_term[i] = sah_term(node, root_half_area);
        d.sah_cost += d.sah_term[i];
        if (is_leaf(node)) continue;
        d.left[i] = std::int32_t(i + 1), d.right[i] = std::int32_t(node.index);
        d.parent[i + 1] = d.parent[node.index] = std::int32_t(i);
        if (half > 0) d.child_overlap[i] = overlap_half_area(bvh.nodes[i + 1], bvh.nodes[node.index]) / half;
    }
    // Up: children come after their parent, so one backward pass sums every subtree.
    for (std::uint32_t i = n; i-- > 0;) {
        const BvhNode& node = bvh.nodes[i];
        if (is_leaf(node)) {
            d.prim_count[i] = leaf_count(node);
            d.subtree_sah[i] = d.sah_term[i];
        } else {
            d.prim_count[i] = d.prim_count[i + 1] + d.prim_count[node.index];
            d.subtree_sah[i] = d.sah_term[i] + d.subtree_sah[i + 1] + d.subtree_sah[node.index];
        }
    }
    for (std::uint32_t i = 0; i < n; ++i) d.sah_share[i] = d.sah_cost > 0 ? d.subtree_sah[i] / d.sah_cost : 0.0;
    if (!epo) {
        d.epo.assign(n, std::numeric_limits<double>::quiet_NaN());
        d.epo_cost = std::numeric_limits<double>::quiet_NaN();
    } else {
        // A TLAS (tlas.h) packs no geometry: its boxes hold instances, whose EPO it cannot clip.
        d.epo = bvh.prims.empty() ? std::vector<double>(n, 0.0) : epo_terms(bvh, threads, cancel);
        for (double e : d.epo) d.epo_cost += e;
    }
    d.surface_area = surface_area(bvh);
    return d;
}

}  // namespace bvhlab
