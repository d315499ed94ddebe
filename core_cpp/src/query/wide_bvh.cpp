#include "bvhlab/wide_bvh.h"

#include <algorithm>
#include <limits>
#include <vector>

namespace bvhlab {
namespace {

/// The binary children of binary node i, opened up to four by largest surface area.
int gather_children(const Bvh& bvh, std::uint32_t i, std::uint32_t out[4]) {
    const BvhNode& n = bvh.nodes[i];
    out[0] = i + 1, out[1] = n.index;
    int count = 2;
    while (count < 4) {
        int pick = -1;
        float best = -1.0f;
        for (int k = 0; k < count; ++k) {
            const BvhNode& c = bvh.nodes[out[k]];
            float area = node_box(c).half_area();
            if (!is_leaf(c) && area > best) best = area, pick = k;
        }
        if (pick < 0) break;
        std::uint32_t opened = out[pick];
        out[pick] = opened + 1;
        out[count++] = bvh.nodes[opened].index;
    }
    return count;
}

}  // namespace

WideBvh make_wide(const Bvh& bvh) {
    WideBvh wide;
    if (bvh.empty()) return wide;
    if (is_leaf(bvh.nodes[0])) {
        wide.root_leaf_count = leaf_count(bvh.nodes[0]);
        return wide;
    }
    wide.nodes.reserve(bvh.nodes.size() / 2 + 1);
    struct Item { std::uint32_t binary, wide; };
    std::vector<Item> stack{{0, 0}};
    wide.nodes.emplace_back();
    const float inf = std::numeric_limits<float>::infinity();
    while (!stack.empty()) {
        Item item = stack.back();
        stack.pop_back();
        std::uint32_t children[4];
        int count = gather_children(bvh, item.binary, children);
        for (int k = 0; k < 4; ++k) {
            WideNode& w = wide.nodes[item.wide];
            if (k >= count) {  // an empty slot: a box no ray can enter
                w.lo_x[k] = w.lo_y[k] = w.lo_z[k] = inf;
                w.hi_x[k] = w.hi_y[k] = w.hi_z[k] = -inf;
                w.child[k] = 0, w.count[k] = 0;
                continue;
            }
            const BvhNode& c = bvh.nodes[children[k]];
            w.lo_x[k] = c.lo.x, w.lo_y[k] = c.lo.y, w.lo_z[k] = c.lo.z;
            w.hi_x[k] = c.hi.x, w.hi_y[k] = c.hi.y, w.hi_z[k] = c.hi.z;
            if (is_leaf(c)) {
                w.child[k] = c.index, w.count[k] = leaf_count(c);
            } else {
                auto index = static_cast<std::uint32_t>(wide.nodes.size());
                wide.nodes.emplace_back();  // may move the array: `w` is not used after this
                wide.nodes[item.wide].child[k] = index, wide.nodes[item.wide].count[k] = 0;
                stack.push_back({children[k], index});
            }
        }
    }
    return wide;
}

}  // namespace bvhlab
