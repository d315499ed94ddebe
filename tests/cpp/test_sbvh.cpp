// The SBVH builder (src/build/sbvh): chopped references hold their parts of the triangle, the tree
// is valid with repeated references, within the budget, the same on every thread count, and its
// settings are checked.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/stats.h"
#include "sbvh/chop.h"
#include "test_scenes.h"

using namespace bvhlab;

namespace {

/// A point of triangle t at barycentrics (u, v), in double.
void point_of(const GeometryView& g, std::size_t t, double u, double v, double p[3]) {
    const Vec3 a = g.vertex(t, 0), b = g.vertex(t, 1), c = g.vertex(t, 2);
    for (int k = 0; k < 3; ++k) p[k] = a[k] * (1 - u - v) + b[k] * u + c[k] * v;
}

bool inside(const Aabb& box, const double p[3]) {
    for (int k = 0; k < 3; ++k)
        if (p[k] < box.lo[k] || p[k] > box.hi[k]) return false;
    return true;
}

test::Scene long_thin_triangles(std::uint32_t n, std::uint32_t seed) {
    test::Scene s = test::random_scene(n, 20, seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 10.0f);
    for (std::uint32_t i = 0; i < n / 5; ++i) {
        const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
        s.add_triangle(a, b, b + Vec3{0.1f, 0.05f, 0.02f});
    }
    return s;
}

BuildConfig sbvh_config(std::uint32_t leaf = 4, unsigned threads = 1) {
    BuildConfig c;
    c.method = SplitMethod::Sbvh, c.max_leaf_size = leaf, c.threads = threads;
    return c;
}

}  // namespace

TEST(Chop, EachPartHoldsTheTrianglePointsOnItsSide) {
    const test::Scene s = long_thin_triangles(200, 3);
    const GeometryView g = s.view();
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    int chopped = 0;
    for (std::size_t t = 0; t < g.triangle_count; ++t) {
        Aabb box;
        for (int k = 0; k < 3; ++k) box.grow(g.vertex(t, k));
        const PrimRef ref{{box.lo.x, box.lo.y, box.lo.z}, std::uint32_t(t), {box.hi.x, box.hi.y, box.hi.z}, 0};
        const int axis = int(t % 3);
        const float pos = box.lo[axis] + u(rng) * (box.hi[axis] - box.lo[axis]);
        Aabb below, above;
        sbvh::chop_reference(g, ref, axis, pos, below, above);
        EXPECT_TRUE(box.contains(below) || below.empty());
        EXPECT_TRUE(box.contains(above) || above.empty());
        chopped += !below.empty() && !above.empty();
        for (int i = 0; i <= 40; ++i)
            for (int j = 0; i + j <= 40; ++j) {
                double p[3];
                point_of(g, t, i / 40.0, j / 40.0, p);
                if (p[axis] <= pos) EXPECT_TRUE(inside(below, p)) << "triangle " << t << " below " << pos;
                if (p[axis] >= pos) EXPECT_TRUE(inside(above, p)) << "triangle " << t << " above " << pos;
            }
        if (box.hi[axis] > pos) EXPECT_LE(below.hi[axis], pos);
    }
    EXPECT_GT(chopped, 100);
}

TEST(Sbvh, ValidTreeWithRepeatedReferencesWithinTheBudget) {
    const test::Scene s = long_thin_triangles(3000, 5);
    const GeometryView g = s.view();
    for (float budget : {1.0f, 1.2f, 1.5f}) {
        BuildConfig c = sbvh_config(2);
        c.sbvh_budget = budget;
        const Bvh bvh = build_bvh(g, c);
        const std::size_t n = g.primitive_count();
        EXPECT_LE(bvh.refs.size(), std::size_t(std::floor(double(budget) * double(n))));
        if (budget == 1.0f) EXPECT_EQ(bvh.refs.size(), n);
        if (budget == 1.5f) EXPECT_GT(bvh.refs.size(), n);
        ASSERT_EQ(bvh.prims.size(), bvh.refs.size());
        ASSERT_EQ(bvh.depths.size(), bvh.nodes.size());
        // layout: children after their parent, skip = end of the subtree, leaves' slots in order
        std::vector<std::uint32_t> end(bvh.nodes.size());
        std::vector<int> seen(n, 0);
        std::uint32_t next_slot = 0;
        for (std::uint32_t i = 0; i < bvh.nodes.size(); ++i) {
            const BvhNode& node = bvh.nodes[i];
            if (!is_leaf(node)) continue;
            EXPECT_EQ(node.index, next_slot);
            EXPECT_LE(leaf_count(node), 2u);
            next_slot += leaf_count(node);
            for (std::uint32_t k = node.index; k < node.index + leaf_count(node); ++k) {
                const std::uint32_t ref = bvh.refs[k];
                ++seen[(ref & gpu::REF_SPHERE_BIT) ? g.triangle_count + ref_index(ref) : ref];
                EXPECT_EQ(bvh.prims[k].ref, ref);
            }
        }
        EXPECT_EQ(next_slot, bvh.refs.size());
        for (std::size_t k = 0; k < n; ++k) EXPECT_GE(seen[k], 1) << "primitive " << k << " unreachable";
        for (std::uint32_t i = std::uint32_t(bvh.nodes.size()); i-- > 0;) {
            const BvhNode& node = bvh.nodes[i];
            if (is_leaf(node)) {
                end[i] = i + 1;
                continue;
            }
            EXPECT_EQ(end[i + 1], node.index);
            EXPECT_TRUE(node_box(node).contains(node_box(bvh.nodes[i + 1])));
            EXPECT_TRUE(node_box(node).contains(node_box(bvh.nodes[node.index])));
            EXPECT_EQ(bvh.depths[i + 1], bvh.depths[i] + 1);
            end[i] = end[node.index];
            EXPECT_EQ(skip_index(node, i), end[i]);
        }
        EXPECT_EQ(end[0], bvh.nodes.size());
        const BvhStats st = compute_stats(bvh);
        EXPECT_EQ(st.references, bvh.refs.size());
        EXPECT_EQ(st.primitives, n);
        EXPECT_LE(st.height, gpu::MAX_TREE_HEIGHT);
    }
}

TEST(Sbvh, LowerSahThanTheBinnedTreeAndTheSameOnEveryThreadCount) {
    const test::Scene s = long_thin_triangles(4000, 9);
    const Bvh one = build_bvh(s.view(), sbvh_config(4, 1));
    BuildConfig binned;
    EXPECT_LT(sah_cost(one), sah_cost(build_bvh(s.view(), binned)));
    for (unsigned threads : {2u, 4u}) {
        const Bvh other = build_bvh(s.view(), sbvh_config(4, threads));
        ASSERT_EQ(other.nodes.size(), one.nodes.size());
        EXPECT_EQ(std::memcmp(other.nodes.data(), one.nodes.data(), one.nodes.size() * sizeof(BvhNode)), 0);
        EXPECT_TRUE(other.refs == one.refs);
    }
}

TEST(Sbvh, BadSettingsAreRefused) {
    const test::Scene s = test::random_scene(20, 0, 1);
    for (float alpha : {-1e-5f, NAN, INFINITY}) {
        BuildConfig c = sbvh_config();
        c.sbvh_alpha = alpha;
        EXPECT_THROW(build_bvh(s.view(), c), std::invalid_argument);
    }
    for (float budget : {0.0f, 0.99f, NAN, INFINITY, 65.0f}) {
        BuildConfig c = sbvh_config();
        c.sbvh_budget = budget;
        EXPECT_THROW(build_bvh(s.view(), c), std::invalid_argument);
    }
}

TEST(Sbvh, ProgressCanCancel) {
    const test::Scene s = long_thin_triangles(20000, 2);
    BuildConfig c = sbvh_config();
    c.progress = [](double done) { return done < 0.1; };
    EXPECT_THROW(build_bvh(s.view(), c), BuildCancelled);
}
