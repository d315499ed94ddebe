// The exact SAH of small ranges (small_subtree.h) against a brute force: every internal node of
// at most `exact` primitives is split where a search over each axis's centroid order, in double
// precision and written independently here, finds the lowest SAH cost (report §2.3.2), with the
// counts in blocks of sah_block above a node of one block (sah.h) and as they are below.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <limits>
#include <numeric>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/split.h"
#include "test_scenes.h"
#include "tree_checks.h"

using namespace bvhlab;
using bvhlab::prim_box;

namespace {

double half_area(const Aabb& b) {
    const double x = double(b.hi.x) - b.lo.x, y = double(b.hi.y) - b.lo.y, z = double(b.hi.z) - b.lo.z;
    return x * y + y * z + z * x;
}

/// n as the SAH counts it in a node of `total` primitives: whole blocks when total > block.
double counted(std::size_t n, std::size_t total, std::uint32_t block) {
    return total > block ? std::ceil(double(n) / block) * block : double(n);
}

/// The lowest 1 + (A_L·N_L + A_R·N_R) / A_P over every cut of the boxes sorted by centroid on each axis.
double brute_force_cost(std::vector<Aabb> boxes, const Aabb& parent, std::uint32_t block) {
    const std::size_t n = boxes.size();
    double best = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
        std::sort(boxes.begin(), boxes.end(),
                  [a](const Aabb& p, const Aabb& q) { return p.lo[a] + p.hi[a] < q.lo[a] + q.hi[a]; });
        for (std::size_t k = 1; k < boxes.size(); ++k) {
            Aabb left, right;
            for (std::size_t i = 0; i < boxes.size(); ++i) (i < k ? left : right).grow(boxes[i]);
            const double cost =
                1.0 + (half_area(left) * counted(k, n, block) + half_area(right) * counted(n - k, n, block)) /
                          half_area(parent);
            best = std::min(best, cost);
        }
    }
    return best;
}

/// Checks the nodes of the subtree at i; returns its primitive count.
std::uint32_t check_exact(const Bvh& bvh, const GeometryView& g, std::uint32_t i, std::uint32_t exact,
                          std::uint32_t block, int& checked) {
    const BvhNode& n = bvh.nodes[i];
    if (is_leaf(n)) return leaf_count(n);
    const std::uint32_t n_left = check_exact(bvh, g, i + 1, exact, block, checked);
    const std::uint32_t n_right = check_exact(bvh, g, n.index, exact, block, checked);
    const std::uint32_t count = n_left + n_right;
    if (count <= exact && count >= 3) {
        std::uint32_t first = i + 1;  // the first leaf of the subtree holds its first reference
        while (!is_leaf(bvh.nodes[first])) ++first;
        std::vector<Aabb> boxes;
        for (std::uint32_t k = bvh.nodes[first].index; k < bvh.nodes[first].index + count; ++k)
            boxes.push_back(prim_box(g, bvh.refs[k]));
        const Aabb parent = node_box(n);
        const double built = 1.0 + (half_area(node_box(bvh.nodes[i + 1])) * counted(n_left, count, block) +
                                    half_area(node_box(bvh.nodes[n.index])) * counted(n_right, count, block)) /
                                       half_area(parent);
        EXPECT_LE(built, brute_force_cost(boxes, parent, block) * (1.0 + 1e-5))
            << "node " << i << " of " << count << ", blocks of " << block;
        ++checked;
    }
    return count;
}

/// The boxes of the primitives of the subtree at i (its leaves are one range of refs).
std::vector<Aabb> subtree_boxes(const Bvh& bvh, const GeometryView& g, std::uint32_t i, std::uint32_t count) {
    std::uint32_t first = i;
    while (!is_leaf(bvh.nodes[first])) ++first;
    std::vector<Aabb> boxes;
    for (std::uint32_t k = bvh.nodes[first].index; k < bvh.nodes[first].index + count; ++k)
        boxes.push_back(prim_box(g, bvh.refs[k]));
    return boxes;
}

/// SAH leaf termination (report §5.1) in the nodes of 2 .. max_leaf primitives that the exact
/// sweep splits: a leaf where a leaf costs no more than the brute force's cheapest split, a split
/// where it costs more, the leaf's count in blocks as the splits' are. Returns the subtree's count.
std::uint32_t check_leaves(const Bvh& bvh, const GeometryView& g, std::uint32_t i, std::uint32_t max_leaf,
                           std::uint32_t block, int& leaves, int& splits) {
    const BvhNode& n = bvh.nodes[i];
    const std::uint32_t count = is_leaf(n) ? leaf_count(n)
                                           : check_leaves(bvh, g, i + 1, max_leaf, block, leaves, splits) +
                                                 check_leaves(bvh, g, n.index, max_leaf, block, leaves, splits);
    if (count >= 2 && count <= max_leaf) {
        const double leaf_cost = counted(count, count, block);
        const double split_cost = brute_force_cost(subtree_boxes(bvh, g, i, count), node_box(n), block);
        if (is_leaf(n)) EXPECT_LE(leaf_cost, split_cost * (1.0 + 1e-5)) << "leaf " << i << " of " << count;
        else EXPECT_GT(leaf_cost, split_cost * (1.0 - 1e-5)) << "node " << i << " of " << count;
        ++(is_leaf(n) ? leaves : splits);
    }
    return count;
}

struct ExactCase {
    SplitMethod method;
    BinBounds bin_bounds;
    std::uint32_t exact;  ///< ranges up to this size get the exact SAH
};

class ExactSah : public ::testing::TestWithParam<ExactCase> {};

TEST_P(ExactSah, SmallNodesSplitAtTheBruteForceOptimum) {
    const ExactCase c = GetParam();
    BuildConfig cfg;
    cfg.method = c.method, cfg.bin_bounds = c.bin_bounds, cfg.axis = AxisPolicy::Best, cfg.max_leaf_size = 1;
    ASSERT_EQ(small_subtree_size(cfg), c.exact);
    for (std::uint32_t block : {1u, 4u, 8u}) {
        cfg.sah_block = block;
        for (std::uint32_t seed : {1u, 2u}) {
            auto scene = test::random_scene(3000, 200, seed);
            for (std::uint32_t threads : {1u, 2u}) {
                cfg.threads = threads;
                Bvh bvh = build_bvh(scene.view(), cfg);
                test::check_tree(bvh, scene.view(), 1);
                int checked = 0;
                check_exact(bvh, scene.view(), 0, c.exact, block, checked);
                EXPECT_GT(checked, 300);
            }
        }
    }
}

TEST_P(ExactSah, LeavesWhereALeafCostsNoMoreThanTheCheapestSplit) {
    const ExactCase c = GetParam();
    BuildConfig cfg;
    cfg.method = c.method, cfg.bin_bounds = c.bin_bounds, cfg.axis = AxisPolicy::Best;
    cfg.max_leaf_size = std::min(c.exact, 8u);
    // large triangles at random in a cube (uniform1m in small): their boxes overlap, so leaves of
    // up to eight are often cheaper than splits and both kinds of node are common
    test::Scene scene;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 10.0f);
    auto point = [&] { return Vec3{u(rng), u(rng), u(rng)}; };
    for (int i = 0; i < 3000; ++i) {
        const Vec3 p = point();
        scene.add_triangle(p, p + (point() - p) * 0.2f, p + (point() - p) * 0.2f);
    }
    for (std::uint32_t block : {1u, 4u}) {
        cfg.sah_block = block;
        Bvh bvh = build_bvh(scene.view(), cfg);
        test::check_tree(bvh, scene.view(), cfg.max_leaf_size);
        int leaves = 0, splits = 0;
        check_leaves(bvh, scene.view(), 0, cfg.max_leaf_size, block, leaves, splits);
        EXPECT_GT(leaves, 50) << "blocks of " << block;
        EXPECT_GT(splits, 50) << "blocks of " << block;
    }
}

INSTANTIATE_TEST_SUITE_P(SahMethods, ExactSah,
                         ::testing::Values(ExactCase{SplitMethod::Sah, BinBounds::Box, kSmallSubtree},
                                           ExactCase{SplitMethod::Sah, BinBounds::Centroids, kSmallExactReport},
                                           ExactCase{SplitMethod::SweepSah, BinBounds::Box, kSmallSubtree}),
                         [](const auto& info) {
                             const ExactCase& c = info.param;
                             return to_string(c.method) + "_" + to_string(c.bin_bounds);
                         });

}  // namespace
