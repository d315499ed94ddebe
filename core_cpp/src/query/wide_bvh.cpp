#include "bvhlab/wide_bvh.h"

#include <limits>
#include <vector>

namespace bvhlab {
namespace {

/// A subtree of at most this many primitives becomes one wide leaf (one packet of triangles).
constexpr std::uint32_t kMergedLeaf = 4;

/// Per binary node: primitives in its subtree and the first of them (leaves are contiguous in
/// leaf order, so a subtree's primitives are one range).
struct SubtreeRanges {
    std::vector<std::uint32_t> first, size;
    explicit SubtreeRanges(const Bvh& bvh) : first(bvh.nodes.size()), size(bvh.nodes.size()) {
        for (std::size_t i = bvh.nodes.size(); i-- > 0;) {
            const BvhNode& n = bvh.nodes[i];
            if (is_leaf(n)) first[i] = n.index, size[i] = leaf_count(n);
            else first[i] = first[i + 1], size[i] = size[i + 1] + size[n.index];
        }
    }
    bool leaf(const Bvh& bvh, std::uint32_t i) const { return is_leaf(bvh.nodes[i]) || size[i] <= kMergedLeaf; }
};

/// Appends the primitives [first, first + n) of bvh.prims as packets (triangles, then spheres,
/// four a packet); returns the first packet's index and sets `count`.
std::uint32_t pack_leaf(const Bvh& bvh, std::uint32_t first, std::uint32_t n, WideBvh& wide, std::uint32_t& count) {
    const auto begin = static_cast<std::uint32_t>(wide.packets.size());
    for (bool spheres : {false, true}) {
        std::uint32_t lane = 4;
        for (std::uint32_t k = first; k < first + n; ++k) {
            const PackedPrim& p = bvh.prims[k];
            if (is_sphere_ref(p.ref) != spheres) continue;
            if (lane == 4) {
                PrimPacket empty{};
                for (auto& r : empty.ref) r = kNoHit;
                wide.packets.push_back(empty);
                wide.slots.insert(wide.slots.end(), 4, kNoHit);
                lane = 0;
            }
            PrimPacket& q = wide.packets.back();
            const gpu::vec3 vertices[3] = {p.v0, p.v1, p.v2};
            for (int v = 0; v < 3; ++v)
                q.v[v][0][lane] = vertices[v].x, q.v[v][1][lane] = vertices[v].y, q.v[v][2][lane] = vertices[v].z;
            q.ref[lane] = p.ref;
            wide.slots[wide.slots.size() - 4 + lane] = k;
            ++lane;
        }
    }
    count = static_cast<std::uint32_t>(wide.packets.size()) - begin;
    return begin;
}

/// The binary children of binary node i, opened up to eight by largest surface area; a node that
/// is itself a leaf (only the root can be) is its own only child.
int gather_children(const Bvh& bvh, const SubtreeRanges& ranges, std::uint32_t i, std::uint32_t out[8]) {
    if (ranges.leaf(bvh, i)) {
        out[0] = i;
        return 1;
    }
    out[0] = i + 1, out[1] = bvh.nodes[i].index;
    int count = 2;
    while (count < 8) {
        int pick = -1;
        float best = -1.0f;
        for (int k = 0; k < count; ++k) {
            const float area = node_box(bvh.nodes[out[k]]).half_area();
            if (!ranges.leaf(bvh, out[k]) && area > best) best = area, pick = k;
        }
        if (pick < 0) break;
        const std::uint32_t opened = out[pick];
        out[pick] = opened + 1;
        out[count++] = bvh.nodes[opened].index;
    }
    return count;
}

void set_slot(WideNode& w, int k, const BvhNode* c) {
    const float inf = std::numeric_limits<float>::infinity();
    w.lo_x[k] = c ? c->lo.x : inf, w.lo_y[k] = c ? c->lo.y : inf, w.lo_z[k] = c ? c->lo.z : inf;
    w.hi_x[k] = c ? c->hi.x : -inf, w.hi_y[k] = c ? c->hi.y : -inf, w.hi_z[k] = c ? c->hi.z : -inf;
    w.child[k] = 0, w.count[k] = 0;
}

}  // namespace

WideBvh make_wide(const Bvh& bvh) {
    WideBvh wide;
    if (bvh.empty()) return wide;
    const SubtreeRanges ranges(bvh);
    wide.packets.reserve(bvh.prims.size() / 2 + 1);
    wide.nodes.reserve(bvh.nodes.size() / 4 + 1);
    struct Item {
        std::uint32_t binary, wide;
    };
    std::vector<Item> stack{{0, 0}};
    wide.nodes.emplace_back();
    while (!stack.empty()) {
        const Item item = stack.back();
        stack.pop_back();
        std::uint32_t children[8];
        const int count = gather_children(bvh, ranges, item.binary, children);
        for (int k = 0; k < 8; ++k) {
            const BvhNode* c = k < count ? &bvh.nodes[children[k]] : nullptr;
            set_slot(wide.nodes[item.wide], k, c);
            if (!c) continue;
            if (ranges.leaf(bvh, children[k])) {
                std::uint32_t packets = 0;
                const std::uint32_t first =
                    pack_leaf(bvh, ranges.first[children[k]], ranges.size[children[k]], wide, packets);
                wide.nodes[item.wide].child[k] = first, wide.nodes[item.wide].count[k] = packets;
            } else {
                const auto index = static_cast<std::uint32_t>(wide.nodes.size());
                wide.nodes.emplace_back();  // may move the array: take references after this only
                wide.nodes[item.wide].child[k] = index;
                stack.push_back({children[k], index});
            }
        }
    }
    return wide;
}

}  // namespace bvhlab
