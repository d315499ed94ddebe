// The 8-wide copy of the tree (wide_bvh.h): its shape against the binary tree it came from, and
// its collapse against every collapse there is, enumerated. The hits it gives are checked against
// brute force in test_traverse.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/wide_bvh.h"
#include "test_scenes.h"

using namespace bvhlab;

namespace {

bool used(const WideNode& w, int k) { return w.lo_x[k] <= w.hi_x[k]; }

Aabb slot_box(const WideNode& w, int k) {
    return {{w.lo_x[k], w.lo_y[k], w.lo_z[k]}, {w.hi_x[k], w.hi_y[k], w.hi_z[k]}};
}

/// Every node of the wide tree, from the root down.
std::vector<const WideNode*> all_nodes(const WideBvh& wide) {
    std::vector<const WideNode*> out;
    std::vector<std::uint32_t> todo{0};
    while (!todo.empty()) {
        const WideNode& w = wide.node(todo.back());
        todo.pop_back();
        out.push_back(&w);
        for (int k = 0; k < 8; ++k)
            if (used(w, k) && !w.leaf(k)) todo.push_back(w.child[k]);
    }
    return out;
}

/// The box of a wide node: the union of its children's boxes (the box of the binary node it was
/// made from, whose box is the union of its children's).
Aabb node_bounds(const WideNode& w) {
    Aabb b;
    for (int k = 0; k < 8; ++k)
        if (used(w, k)) b.grow(slot_box(w, k));
    return b;
}

/// The least total surface area of wide nodes over every way of collapsing the binary tree, by
/// enumeration: a wide node made from binary node n takes as children any set of at most eight
/// binary nodes that covers n's subtree exactly (a cut of it below n); a merged leaf (a binary
/// leaf, or a subtree of at most four primitives) is never opened. Written apart from the
/// collapse's own recurrence: every cut is listed, none is derived from another's cost.
class Enumeration {
public:
    explicit Enumeration(const Bvh& bvh) : bvh_(bvh) {}

    float best_wide(std::uint32_t n) {
        if (auto it = memo_.find(n); it != memo_.end()) return it->second;
        float best = INFINITY;
        for (const auto& cut : cuts_below(n)) {
            float cost = 0;
            for (std::uint32_t c : cut)
                if (!merged(c)) cost += best_wide(c);
            best = std::min(best, cost);
        }
        return memo_[n] = node_box(bvh_.nodes[n]).half_area() + best;
    }

    bool merged(std::uint32_t n) const { return is_leaf(bvh_.nodes[n]) || primitives(n) <= 4; }

private:
    std::uint32_t primitives(std::uint32_t n) const {
        const BvhNode& node = bvh_.nodes[n];
        return is_leaf(node) ? leaf_count(node) : primitives(n + 1) + primitives(node.index);
    }

    /// Every set of at most eight nodes that covers n's subtree: n itself, or a cover of each child.
    std::vector<std::vector<std::uint32_t>> covers(std::uint32_t n, std::size_t most) const {
        std::vector<std::vector<std::uint32_t>> out{{n}};
        if (merged(n) || most < 2) return out;
        for (const auto& a : covers(n + 1, most - 1))
            for (const auto& b : covers(bvh_.nodes[n].index, most - a.size())) {
                auto both = a;
                both.insert(both.end(), b.begin(), b.end());
                out.push_back(both);
            }
        return out;
    }

    /// The children a wide node made from n may have: covers of n's subtree other than {n}.
    std::vector<std::vector<std::uint32_t>> cuts_below(std::uint32_t n) const {
        auto all = covers(n, 8);
        all.erase(all.begin());
        return all;
    }

    const Bvh& bvh_;
    std::map<std::uint32_t, float> memo_;
};

Bvh small_tree(std::uint32_t triangles, std::uint32_t seed, SplitMethod method, std::uint32_t leaf) {
    const test::Scene s = test::random_scene(triangles, triangles / 8, seed);
    BuildConfig c;
    c.method = method;
    c.max_leaf_size = leaf;
    return build_bvh(s.view(), c);
}

}  // namespace

TEST(WideBvh, PreorderLinesHoldEveryPrimitiveOnceAndEveryNodeOnce) {
    for (std::uint32_t leaf : {1u, 4u, 8u}) {
        const Bvh bvh = small_tree(5000, 3 + leaf, SplitMethod::Sah, leaf);
        const WideBvh wide = make_wide(bvh);
        // Walking from the root in preorder lays the lines down again, one after another: each
        // node, then its leaves' packets in slot order, then its inner children's subtrees.
        std::vector<int> seen(bvh.prims.size(), 0);
        std::uint32_t next = 0, nodes = 0, packets = 0;
        std::vector<std::uint32_t> todo{0};
        while (!todo.empty()) {
            const std::uint32_t line = todo.back();
            todo.pop_back();
            ASSERT_EQ(line, next) << "leaf " << leaf;
            const WideNode& w = wide.node(line);
            next += kNodeLines, ++nodes;
            int children = 0;
            std::vector<std::uint32_t> inner;
            for (int k = 0; k < 8; ++k) {
                if (!used(w, k)) continue;
                ++children;
                if (!w.leaf(k)) {
                    inner.push_back(w.child[k]);
                    continue;
                }
                ASSERT_EQ(w.line(k), next);
                for (bool more = true; more; next += kPacketLines, ++packets) {
                    const PrimPacket& q = wide.packet(next);
                    more = q.more != 0;
                    for (int l = 0; l < 4; ++l) {
                        if (q.ref[l] == kNoHit) continue;
                        ASSERT_LT(q.slot[l], bvh.prims.size());
                        EXPECT_EQ(q.ref[l], bvh.prims[q.slot[l]].ref);
                        ++seen[q.slot[l]];
                    }
                }
            }
            EXPECT_GE(children, 1);
            todo.insert(todo.end(), inner.rbegin(), inner.rend());
        }
        EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), std::ptrdiff_t(seen.size())) << "leaf " << leaf;
        EXPECT_EQ(next, wide.lines.size());
        EXPECT_EQ(wide.lines.capacity(), wide.lines.size());  // counted exactly: one block, advised before use
        EXPECT_EQ(nodes, wide.node_count);
        EXPECT_EQ(packets, wide.packet_count);
    }
}

TEST(WideBvh, CollapseHasTheLeastWideNodeAreaOfAllCollapses) {
    // Small trees, so that every cut can be listed; several methods, so that the trees differ in shape.
    int checked = 0;
    for (std::uint32_t seed = 1; seed <= 6; ++seed)
        for (SplitMethod method : {SplitMethod::Sah, SplitMethod::Median, SplitMethod::Lbvh}) {
            const Bvh bvh = small_tree(36 + 4 * seed, seed, method, 1 + seed % 2);
            const WideBvh wide = make_wide(bvh);
            Enumeration all(bvh);
            if (all.merged(0)) continue;
            double area = 0;
            for (const WideNode* w : all_nodes(wide)) area += node_bounds(*w).half_area();
            const float best = all.best_wide(0);
            EXPECT_NEAR(area, best, 1e-5 * best) << to_string(method) << " seed " << seed;
            ++checked;
        }
    EXPECT_EQ(checked, 18);
}
