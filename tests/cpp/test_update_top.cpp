// The top's cut with intact subtrees (update.h top_intact_primitives, rebuild_top.h top_cut):
// subtrees that moved as one are taken whole, every primitive stays under exactly one cut node,
// and adaptive's tree over such a cut is valid, costs what its stats say and is the same on every
// thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "bvhlab/stats.h"
#include "bvhlab/update.h"
#include "rebuild_top.h"
#include "test_scenes.h"
#include "tree_checks.h"

using namespace bvhlab;
using namespace bvhlab::test;

namespace {

constexpr int kSpheres = 24;

/// `kSpheres` octaspheres in a row along x; `moved`: sphere k translated whole by its own offset
/// (rigid parts, some moved past others), the same triangles in the same order.
Scene spheres(bool moved) {
    Scene s;
    for (int k = 0; k < kSpheres; ++k) {
        const float dx = moved ? 7.0f * std::sin(float(5 * k + 1)) : 0.0f, dy = moved ? float(k % 4) : 0.0f;
        const Scene part = octasphere(4, Vec3{3.0f * float(k) + dx, dy, 0.5f * dx});
        s.triangles.insert(s.triangles.end(), part.triangles.begin(), part.triangles.end());
    }
    return s;
}

/// The spheres built at rest, the costs when built, and the tree refitted to the moved spheres
/// with its costs now: what the cut is taken over.
struct MovedSpheres {
    Scene rest = spheres(false), moved = spheres(true);
    Bvh tree = build_bvh(rest.view());
    NodeCostArray built = subtree_costs(tree);
    Bvh refit = refitted(tree, moved.view());
    NodeCosts now = node_costs(refit);
};

/// The primitives under node i and the subtree's cost S/A, by recursion (independent of
/// node_costs): S(leaf) = A·N, S(inner) = A + S(children).
double area_cost_of(const Bvh& bvh, std::uint32_t i, std::vector<std::uint32_t>& prims) {
    const BvhNode& n = bvh.nodes[i];
    const double a = node_box(n).half_area();
    if (is_leaf(n)) {
        prims.insert(prims.end(), bvh.refs.begin() + n.index, bvh.refs.begin() + n.index + leaf_count(n));
        return a * leaf_count(n);
    }
    return a + area_cost_of(bvh, i + 1, prims) + area_cost_of(bvh, n.index, prims);
}

}  // namespace

TEST(UpdateTop, TheCutTakesSubtreesThatMovedAsOneWhole) {
    const MovedSpheres m;
    const std::vector<RebuiltPart> none;
    const PartedTree parted(m.refit, m.now, none, &m.built);
    const std::vector<PartNode> fine = top_cut(parted, 8), coarse = top_cut(parted, 8, 4096);
    EXPECT_LT(4 * coarse.size(), fine.size());  // each sphere (1,024 triangles here) about one box
    const std::uint32_t per_sphere = std::uint32_t(m.rest.triangles.size() / 9 / kSpheres);
    std::vector<int> seen(m.rest.triangles.size() / 9, 0);
    std::size_t whole = 0;
    for (const PartNode& c : coarse) {
        ASSERT_EQ(c.part, -1);
        std::vector<std::uint32_t> prims;
        const double area = node_box(m.refit.nodes[c.node]).half_area();
        const double cost = area_cost_of(m.refit, c.node, prims) / area;
        for (std::uint32_t p : prims) ++seen[p];
        if (prims.size() <= 8 || is_leaf(m.refit.nodes[c.node])) continue;
        ++whole;
        // taken whole: as built (the cost when built, by the same rule on the tree as built), and
        // so all of one rigid sphere
        std::vector<std::uint32_t> unused;
        const double was = area_cost_of(m.tree, c.node, unused) / node_box(m.tree.nodes[c.node]).half_area();
        EXPECT_NEAR(cost, was, 2e-5 * was) << "cut node " << c.node;
        EXPECT_LE(prims.size(), 4096u);
        for (std::uint32_t p : prims) EXPECT_EQ(p / per_sphere, prims.front() / per_sphere) << "cut node " << c.node;
    }
    EXPECT_GT(whole, std::size_t(kSpheres / 2));
    for (std::size_t p = 0; p < seen.size(); ++p) ASSERT_EQ(seen[p], 1) << "primitive " << p;
    // the top over the coarse cut: its cost said before the copy (top_sah_cost, which adaptive
    // weighs against the fine cut's) is the tree's after it
    Bvh copy = m.refit;
    NodeCostArray copy_built = m.built;
    const CutInfo info = cut_info(parted, coarse);
    const Bvh top = built_top(copy.config, info);
    double sah = 0;
    ASSERT_TRUE(rebuild_top(copy, copy_built, parted, coarse, info, top, sah));
    check_tree(copy, m.moved.view(), m.tree.config.max_leaf_size);
    EXPECT_NEAR(top_sah_cost(top, info), sah, 1e-6 * sah);
    EXPECT_NEAR(sah, sah_cost(copy), 1e-4 * sah);
    // without the costs when built, only the fine cut
    const PartedTree unknown(m.refit, m.now, none);
    EXPECT_EQ(top_cut(unknown, 8, 4096).size(), fine.size());
}

TEST(UpdateTop, TwoCutsFromOneScanAreTheCutsOfTwoScans) {
    // adaptive takes its first cut and, where that is dense, a coarser one from one scan: the fine
    // cut until it passes `dense` nodes (then its beginning), the coarse cut whole, with and
    // without rebuilt parts standing in for subtrees
    const MovedSpheres m;
    std::vector<std::uint32_t> roots;  // every other node at depth 4
    for (std::uint32_t i = 0, k = 0; i < m.refit.node_count(); ++i)
        if (m.refit.depths[i] == 4 && k++ % 2 == 0) roots.push_back(i);
    double saved = 0;
    const std::vector<RebuiltPart> none, parts = build_parts(m.refit, roots, m.moved.view(), m.now, saved);
    ASSERT_GT(parts.size(), 3u);
    int differ = 0;  // cases whose two cuts differ (with intact subtrees whole, rigid spheres' may not)
    for (const std::vector<RebuiltPart>* with : {&none, &parts}) {
        const PartedTree parted(m.refit, m.now, *with, &m.built);
        for (const std::uint32_t intact : {0u, 64u}) {
            const std::vector<PartNode> fine = top_cut(parted, 4, intact), coarse = top_cut(parted, 24, intact);
            ASSERT_GE(fine.size(), coarse.size());
            differ += fine.size() > coarse.size();
            for (const std::size_t dense :
                 {std::size_t(0), std::size_t(3), fine.size() / 2, fine.size() - 1, fine.size(), SIZE_MAX}) {
                std::vector<PartNode> got_fine, got_coarse;
                const bool past = top_cuts(parted, 4, 24, intact, dense, got_fine, got_coarse);
                EXPECT_EQ(past, fine.size() > dense);
                EXPECT_TRUE(got_coarse == coarse);
                ASSERT_EQ(got_fine.size(), past ? dense + 1 : fine.size());
                EXPECT_TRUE(std::equal(got_fine.begin(), got_fine.end(), fine.begin()));
            }
        }
    }
    EXPECT_GE(differ, 2);
    std::vector<PartNode> a, b;
    EXPECT_THROW(top_cuts(PartedTree(m.refit, m.now, none), 24, 4, 0, SIZE_MAX, a, b), std::invalid_argument);
}

TEST(UpdateTop, AdaptiveOverIntactSubtreesIsValidAndTheSameOnEveryThreadCount) {
    const Scene rest = spheres(false), moved = spheres(true);
    std::vector<Bvh> trees;
    std::vector<UpdateStats> stats;
    for (std::uint32_t threads : {1u, 4u}) {
        Bvh tree = build_bvh(rest.view());
        tree.config.threads = threads;
        UpdateConfig c;  // adaptive, with the top always rebuilt and never the whole tree
        c.top_growth = 1.0f, c.tree_growth = 100.0f, c.top_intact_primitives = 4096, c.measure_fresh = true;
        NodeCostArray out;
        UpdateStats s;
        trees.push_back(update_bvh(tree, subtree_costs(tree), moved.view(), c, out, &s));
        stats.push_back(s);
        SCOPED_TRACE(threads);
        check_tree(trees.back(), moved.view(), tree.config.max_leaf_size);
        EXPECT_EQ(out.size(), trees.back().nodes.size() + 2);
        EXPECT_NEAR(s.sah_cost, sah_cost(trees.back()), 1e-4 * s.sah_cost);
        EXPECT_LT(s.sah_cost, 1.1 * s.fresh_sah_cost);
    }
    ASSERT_EQ(stats[0].policy, UpdatePolicy::Partial);
    EXPECT_GT(stats[0].top_boxes, 1u);
    EXPECT_EQ(stats[0].top_boxes, stats[1].top_boxes);
    ASSERT_EQ(trees[0].nodes.size(), trees[1].nodes.size());
    EXPECT_EQ(std::memcmp(trees[0].nodes.data(), trees[1].nodes.data(), trees[0].nodes.size() * sizeof(BvhNode)), 0);
    EXPECT_EQ(std::memcmp(trees[0].refs.data(), trees[1].refs.data(), trees[0].refs.size() * 4), 0);
    // the fine cut over the same update: more boxes for the top
    Bvh tree = build_bvh(rest.view());
    UpdateConfig c;
    c.top_growth = 1.0f, c.tree_growth = 100.0f, c.top_intact_primitives = 0, c.top_coarse_cut_primitives = 0;
    NodeCostArray out;
    UpdateStats fine;
    update_bvh(tree, subtree_costs(tree), moved.view(), c, out, &fine);
    EXPECT_GT(fine.top_boxes, 2 * stats[0].top_boxes);
}

TEST(UpdateTop, TheCoarseCutIsTriedFirstAndTheFineOneWhereItWouldPassTreeGrowth) {
    const Scene rest = spheres(false), moved = spheres(true);
    const Bvh tree = build_bvh(rest.view());
    const NodeCostArray built = subtree_costs(tree);
    // adaptive's goal: the root's cost when built, kept as A·cost where the root grew (update_bvh.cpp)
    const double a0 = node_box(tree.nodes[0]).half_area(),
                 a1 = node_box(refitted(tree, moved.view()).nodes[0]).half_area();
    const double goal = built[0] * (a1 > a0 ? a0 / a1 : 1.0);
    auto update = [&](std::uint32_t coarse, float tree_growth, unsigned threads, UpdateStats& s) {
        Bvh t = tree;
        t.config.threads = threads;
        UpdateConfig c;  // the top always rebuilt; no intact subtrees: the coarse cut by size alone
        c.top_growth = 1.0f, c.tree_growth = tree_growth, c.top_intact_primitives = 0;
        c.top_coarse_cut_primitives = coarse;
        NodeCostArray out;
        Bvh u = update_bvh(t, built, moved.view(), c, out, &s);
        check_tree(u, moved.view(), tree.config.max_leaf_size);
        EXPECT_NEAR(s.sah_cost, sah_cost(u), 1e-4 * s.sah_cost);
        return u;
    };
    UpdateStats fine, coarse, coarse4, fallback;
    // subtrees of up to 1,024 primitives (a sphere's): a top over few boxes, dearer than the fine one
    const std::uint32_t kCoarse = 1024;
    update(0, 100.0f, 1, fine);
    const Bvh one = update(kCoarse, 100.0f, 1, coarse), four = update(kCoarse, 100.0f, 4, coarse4);
    ASSERT_EQ(fine.policy, UpdatePolicy::Partial);
    ASSERT_EQ(coarse.policy, UpdatePolicy::Partial);
    EXPECT_LT(2 * coarse.top_boxes, fine.top_boxes);  // fewer boxes
    // the same on every thread count
    EXPECT_EQ(coarse.top_boxes, coarse4.top_boxes);
    ASSERT_EQ(one.nodes.size(), four.nodes.size());
    EXPECT_EQ(std::memcmp(one.nodes.data(), four.nodes.data(), one.nodes.size() * sizeof(BvhNode)), 0);
    // a tree_growth between what the two tops reach: the coarse top would pass it, so the fine one runs
    ASSERT_GT(coarse.sah_cost, fine.sah_cost);
    ASSERT_GT(fine.sah_cost, goal);
    const double between = 0.5 * (coarse.sah_cost + fine.sah_cost) / goal;
    update(kCoarse, float(between), 1, fallback);
    EXPECT_EQ(fallback.policy, UpdatePolicy::Partial);
    EXPECT_EQ(fallback.top_boxes, fine.top_boxes);
    EXPECT_NEAR(fallback.sah_cost, fine.sah_cost, 1e-6 * fine.sah_cost);
}
