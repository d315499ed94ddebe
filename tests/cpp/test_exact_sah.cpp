// The exact SAH of small ranges (small_subtree.h) against a brute force: every internal node of
// at most `exact` primitives is split where a search over each axis's centroid order, in double
// precision and written independently here, finds the lowest SAH cost (report §2.3.2), with the
// counts in blocks of sah_block above a node of one block (sah.h) and as they are below.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/split.h"
#include "test_scenes.h"
#include "tree_checks.h"

using namespace bvhlab;
using bvhlab::test::prim_box;

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

INSTANTIATE_TEST_SUITE_P(SahMethods, ExactSah,
                         ::testing::Values(ExactCase{SplitMethod::Sah, BinBounds::Box, kSmallSubtree},
                                           ExactCase{SplitMethod::Sah, BinBounds::Centroids, kSmallExactReport},
                                           ExactCase{SplitMethod::SweepSah, BinBounds::Box, kSmallSubtree}),
                         [](const auto& info) {
                             const ExactCase& c = info.param;
                             return to_string(c.method) + "_" + to_string(c.bin_bounds);
                         });

}  // namespace
