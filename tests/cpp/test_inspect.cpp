// The inspector's core (issue 35): node data, traversal records and restored trees, in C++ so that
// the sanitizer builds run them (make asan-test): hostile saved trees are refused, never misread.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>

#include "bvhlab/coordinate_range.h"
#include "bvhlab/node_data.h"
#include "bvhlab/ray_record.h"
#include "bvhlab/restore.h"
#include "bvhlab/stats.h"
#include "test_scenes.h"
#include "tree_checks.h"

namespace bvhlab {
namespace {

SavedTree saved_of(const Bvh& bvh) {
    SavedTree s;
    s.nodes.assign(bvh.nodes.begin(), bvh.nodes.end());
    s.refs.assign(bvh.refs.begin(), bvh.refs.end());
    s.geometry_fingerprint = bvh.fingerprint();
    s.config = bvh.config;
    s.build_ms = bvh.build_ms;
    return s;
}

TEST(NodeData, SumsAndCounts) {
    test::Scene scene = test::random_scene(500, 40, 3);
    BuildConfig config;
    config.max_leaf_size = 3;
    Bvh bvh = build_bvh(scene.view(), config);
    NodeData d = compute_node_data(bvh, 2);
    ASSERT_EQ(d.depth.size(), bvh.nodes.size());
    EXPECT_NEAR(d.sah_cost, sah_cost(bvh), 1e-9 * d.sah_cost);
    EXPECT_NEAR(d.subtree_sah[0], d.sah_cost, 1e-9 * d.sah_cost);
    EXPECT_EQ(d.prim_count[0], 540u);
    EXPECT_GT(d.epo_cost, 0.0);
    NodeData one = compute_node_data(bvh, 1);
    EXPECT_EQ(one.epo, d.epo);  // fixed-point sums: the same for any number of threads
    // without the EPO pass: the rest the same, the EPO terms NaN (not zeros that read as figures)
    NodeData rest = compute_node_data(bvh, 2, nullptr, false);
    EXPECT_EQ(rest.lo, d.lo);
    EXPECT_EQ(rest.parent, d.parent);
    EXPECT_EQ(rest.prim_count, d.prim_count);
    EXPECT_EQ(rest.subtree_sah, d.subtree_sah);
    EXPECT_EQ(rest.child_overlap, d.child_overlap);
    EXPECT_EQ(rest.surface_area, d.surface_area);
    ASSERT_EQ(rest.epo.size(), d.epo.size());
    for (double e : rest.epo) ASSERT_TRUE(std::isnan(e));
    EXPECT_TRUE(std::isnan(rest.epo_cost));
}

TEST(NodeData, ClippedArea) {
    const double a[3] = {0, 0, 0}, b[3] = {2, 0, 0}, c[3] = {0, 2, 0};
    const double lo[3] = {0, 0, -1}, hi[3] = {1, 1, 1};
    EXPECT_NEAR(clipped_triangle_area(a, b, c, lo, hi), 1.0, 1e-15);  // the unit square lies inside
    const double lo2[3] = {1, 1, -1}, hi2[3] = {3, 3, 1};
    EXPECT_NEAR(clipped_triangle_area(a, b, c, lo2, hi2), 0.0, 1e-15);  // touches at one point
    const double lo3[3] = {-5, -5, 0.5}, hi3[3] = {5, 5, 1};
    EXPECT_EQ(clipped_triangle_area(a, b, c, lo3, hi3), 0.0);  // above the plane
}

TEST(RayRecord, CountsEqualIntersect) {
    test::Scene scene = test::random_scene(800, 30, 9);
    Bvh bvh = build_bvh(scene.view());
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (int i = 0; i < 500; ++i) {
        Ray ray{{5 + 8 * u(rng), 5 + 8 * u(rng), 5 + 8 * u(rng)}, {u(rng), u(rng), u(rng) + 0.01f}};
        for (Traversal mode : {Traversal::Stack, Traversal::Stackless}) {
            std::uint32_t visited = 0;
            const Hit hit = intersect(bvh, ray, mode, &visited);
            const TraversalRecord r = record_traversal(bvh, ray, mode);
            ASSERT_EQ(r.box_nodes.size(), visited);
            ASSERT_EQ(r.hit.ref, hit.ref);
            ASSERT_EQ(r.hit.t, hit.t);
            if (hit.ref == kNoHit) continue;
            const BvhNode& leaf = bvh.nodes[r.hit_leaf];
            ASSERT_TRUE(is_leaf(leaf));
            ASSERT_TRUE(leaf.index <= r.hit.slot && r.hit.slot < leaf.index + leaf_count(leaf));
        }
    }
    EXPECT_THROW(record_traversal(bvh, Ray{{0, 0, 0}, {1, 0, 0}}, Traversal::Wide), std::invalid_argument);
}

/// Each node's subtree as a range of leaf-order slots: [first, first + count).
struct SlotRanges {
    std::vector<std::uint32_t> first, count;
    explicit SlotRanges(const Bvh& bvh) : first(bvh.nodes.size()), count(bvh.nodes.size()) {
        for (std::size_t i = bvh.nodes.size(); i-- > 0;) {
            const BvhNode& n = bvh.nodes[i];
            if (is_leaf(n)) first[i] = n.index, count[i] = leaf_count(n);
            else first[i] = first[i + 1], count[i] = count[i + 1] + count[n.index];
        }
    }
    bool holds(std::uint32_t node, std::uint32_t slot) const {
        return first[node] <= slot && slot < first[node] + count[node];
    }
};

/// The closest hit over every primitive (no tree), t in the ray's own units.
Hit brute_force(const Bvh& bvh, Ray ray) {
    const float t_scale = scale_ray(ray);
    const RayQuery q(ray);
    Hit hit;
    hit.t = ray.tmax;
    for (std::uint32_t k = 0; k < bvh.prims.size(); ++k)
        if (hit_prim(bvh.prims[k], q, hit)) hit.slot = k;
    hit.t = hit.ref == kNoHit ? kInfinity : hit.t * t_scale;
    return hit;
}

TEST(RayRecord, WideWalkEqualsIntersectWide) {
    test::Scene scene = test::random_scene(900, 40, 12);
    Bvh bvh = build_bvh(scene.view());
    const WideBvh wide = make_wide(bvh);
    const WideNames names = name_wide_nodes(bvh, wide);
    const SlotRanges ranges(bvh);
    EXPECT_EQ(names.at(0), 0u);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    int hits = 0;
    for (int i = 0; i < 500; ++i) {
        Ray ray{{5 + 8 * u(rng), 5 + 8 * u(rng), 5 + 8 * u(rng)}, {u(rng), u(rng), u(rng) + 0.01f}};
        if (i % 2) {  // half of them at a primitive's first vertex or centre
            const PackedPrim& p = bvh.prims[rng() % bvh.prims.size()];
            const Vec3 at{p.v0.x, p.v0.y, p.v0.z};
            ray.dir = at - ray.origin;
        }
        std::uint32_t visited = 0;
        const Hit hit = intersect_wide(wide, bvh, ray, &visited);
        const TraversalRecord r = record_wide_traversal(bvh, wide, names, ray);
        ASSERT_EQ(r.nodes_visited, visited);
        ASSERT_EQ(r.wide_nodes.size(), visited);
        ASSERT_EQ(r.box_wide_step.size(), r.box_nodes.size());
        ASSERT_EQ(r.hit.ref, hit.ref);
        ASSERT_EQ(r.hit.t, hit.t);
        const Hit brute = brute_force(bvh, ray);
        ASSERT_EQ(r.hit.ref, brute.ref);
        ASSERT_EQ(r.hit.t, brute.t);
        // every wide node after the root was entered as a child box of a node visited before it
        for (std::size_t w = 1; w < r.wide_nodes.size(); ++w) {
            bool entered_before = false;
            for (std::size_t b = 0; b < r.box_nodes.size() && r.box_wide_step[b] < w; ++b)
                entered_before |= r.box_nodes[b] == r.wide_nodes[w] && r.box_hit[b];
            ASSERT_TRUE(entered_before) << "wide node " << w;
        }
        if (hit.ref == kNoHit) {
            ASSERT_EQ(r.hit_leaf, kNoHit);
            continue;
        }
        ++hits;
        ASSERT_TRUE(ranges.holds(r.hit_leaf, r.hit.slot));
        ASSERT_LE(ranges.count[r.hit_leaf], 4u);  // a wide leaf: a subtree of at most four
        // the last test that came closer is the hit, in the hit's leaf
        std::size_t last = r.prim_closer.size();
        while (last-- > 0 && !r.prim_closer[last]) {}
        ASSERT_LT(last, r.prim_closer.size());
        ASSERT_EQ(r.prim_slots[last], r.hit.slot);
        ASSERT_EQ(r.prim_leaf[last], r.hit_leaf);
    }
    EXPECT_GT(hits, 100);
}

TEST(Restore, RoundTrip) {
    test::Scene scene = test::random_scene(300, 20, 5);
    Bvh bvh = build_bvh(scene.view());
    Bvh back = restore_bvh(saved_of(bvh), scene.view());
    test::check_tree(back, scene.view(), bvh.config.max_leaf_size);
    ASSERT_EQ(back.nodes.size(), bvh.nodes.size());
    EXPECT_EQ(std::memcmp(back.nodes.data(), bvh.nodes.data(), bvh.nodes.size() * sizeof(BvhNode)), 0);
    EXPECT_EQ(std::memcmp(back.prims.data(), bvh.prims.data(), bvh.prims.size() * sizeof(PackedPrim)), 0);
    EXPECT_EQ(std::vector<std::uint8_t>(back.depths.begin(), back.depths.end()),
              std::vector<std::uint8_t>(bvh.depths.begin(), bvh.depths.end()));
}

/// Random bytes changed in the nodes and references: each such tree is refused, or is a valid tree
/// (a change that keeps every invariant, e.g. a box grown within its parent). Never a crash; the
/// sanitizer builds check that no read goes astray.
TEST(Restore, DamagedTreesAreRefusedOrValid) {
    test::Scene scene = test::random_scene(200, 10, 8);
    BuildConfig config;
    config.max_leaf_size = 2;
    const Bvh bvh = build_bvh(scene.view(), config);
    std::mt19937 rng(1);
    int refused = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        SavedTree s = saved_of(bvh);
        const int flips = 1 + int(rng() % 3);
        for (int f = 0; f < flips; ++f) {
            if (rng() % 4 == 0) {
                s.refs[rng() % s.refs.size()] ^= 1u << (rng() % 32);
            } else {
                auto* bytes = reinterpret_cast<std::uint8_t*>(s.nodes.data());
                bytes[rng() % (s.nodes.size() * sizeof(BvhNode))] ^= std::uint8_t(1u << (rng() % 8));
            }
        }
        try {
            Bvh back = restore_bvh(std::move(s), scene.view(), 1);
            test::check_tree(back, scene.view(), 0x7fffffff);
        } catch (const std::invalid_argument&) { ++refused; }
    }
    EXPECT_GT(refused, 2000);
    SavedTree other = saved_of(bvh);
    other.geometry_fingerprint ^= 1;
    EXPECT_THROW(restore_bvh(other, scene.view()), std::invalid_argument);
}

}  // namespace
}  // namespace bvhlab
