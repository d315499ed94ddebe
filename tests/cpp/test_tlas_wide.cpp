// The TLAS's 8-wide copy (wide_bvh.h make_wide_tlas) and Traversal::Wide's walk of it: every
// binary leaf is the child of exactly one wide node, each child box is the box of the binary node
// it names, and the hits through it equal those of the binary TLAS walk (Traversal::Stack, whose
// BLAS walk gives the wide BLAS walk's hits bit for bit) in t, primitive, instance and u, v; its
// any-hit walk finds exactly the hits before tmax.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "two_level_fixture.h"

using namespace bvhlab;
using namespace bvhlab::test;

namespace {

/// `count` instances of two random meshes, rotated, scaled (some mirrored) and scattered through a
/// cube 120 wide; `leaf_size` instances at most per TLAS leaf.
struct Field : TwoLevelFixture {
    Field(std::uint32_t count, std::uint32_t leaf_size, std::uint32_t seed) {
        meshes.push_back(random_scene(60, 0, seed));
        meshes.push_back(random_scene(200, 0, seed + 1));
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        std::vector<std::uint32_t> blas_of;
        std::vector<Transform> transforms;
        for (std::uint32_t i = 0; i < count; ++i) {
            blas_of.push_back(i % 3 == 0);
            const float s = 0.3f + u(rng);
            transforms.push_back(make_transform({u(rng) - 0.5f, u(rng) - 0.5f, u(rng) + 0.1f}, 6.28f * u(rng),
                                                {i % 5 == 0 ? -s : s, s * (0.5f + u(rng)), s},
                                                {120 * u(rng), 120 * u(rng), 120 * u(rng)}));
        }
        BuildConfig config = default_tlas_config();
        config.max_leaf_size = leaf_size;
        build_two_level(blas_of, transforms, config);
    }
};

Aabb slot_box(const WideNode& n, int k) {
    return {{n.lo_x[k], n.lo_y[k], n.lo_z[k]}, {n.hi_x[k], n.hi_y[k], n.hi_z[k]}};
}

bool same_box(const Aabb& a, const Aabb& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_wide_copy_of(const Tlas& tlas) {
    const Bvh& tree = tlas.tree;
    std::vector<int> leaves(tree.node_count(), 0);
    std::vector<int> nodes_reached(tlas.wide.node_count, 0);
    ASSERT_EQ(tlas.wide.lines.size(), std::size_t(kNodeLines) * tlas.wide.node_count);
    ASSERT_EQ(tlas.wide.node(0).unused[1], 0u);  // the root stands for the binary root
    for (std::uint32_t w = 0; w < tlas.wide.node_count; ++w) {
        const WideNode& n = tlas.wide.node(w * kNodeLines);
        const std::uint32_t count = n.unused[0];
        ASSERT_GE(count, 1u);
        ASSERT_LE(count, 8u);
        for (std::uint32_t k = 0; k < 8; ++k) {
            if (k >= count) {  // an empty slot: an inverted box no ray enters
                EXPECT_GT(n.lo_x[k], n.hi_x[k]);
                continue;
            }
            const std::uint32_t c = n.child[k];
            std::uint32_t binary;
            if (c & kLeafChild) {  // the leaf's first instance in leaf_instances, which names the leaf
                const std::uint32_t first = c & ~kLeafChild;
                ASSERT_LT(first, tlas.leaf_instances.size());
                binary = tlas.leaf_instances[first].leaf;
                ASSERT_LT(binary, tree.node_count());
                ASSERT_TRUE(is_leaf(tree.nodes[binary]));
                EXPECT_EQ(first, tree.nodes[binary].index);
                ++leaves[binary];
            } else {
                ASSERT_EQ(c % kNodeLines, 0u);
                ASSERT_LT(c / kNodeLines, tlas.wide.node_count);
                ++nodes_reached[c / kNodeLines];
                binary = tlas.wide.node(c).unused[1];
                ASSERT_LT(binary, tree.node_count());
                EXPECT_FALSE(is_leaf(tree.nodes[binary]));
            }
            EXPECT_TRUE(same_box(slot_box(n, int(k)), node_box(tree.nodes[binary])));
        }
    }
    for (std::uint32_t i = 0; i < tree.node_count(); ++i)
        EXPECT_EQ(leaves[i], is_leaf(tree.nodes[i]) ? 1 : 0) << "binary node " << i;
    // leaf_instances: each ref's instance as it stands in tlas.instances, its leaf, the last flagged
    ASSERT_EQ(tlas.leaf_instances.size(), tree.refs.size());
    for (std::uint32_t i = 0; i < tree.node_count(); ++i) {
        const BvhNode& n = tree.nodes[i];
        if (!is_leaf(n)) continue;
        for (std::uint32_t k = n.index, end = n.index + leaf_count(n); k < end; ++k) {
            const LeafInstance& e = tlas.leaf_instances[k];
            const Instance& inst = tlas.instances[tree.refs[k]];
            EXPECT_EQ(e.instance, tree.refs[k]);
            EXPECT_EQ(e.blas, inst.blas);
            // the inverse's linear part, and in its fourth column the object's origin in the world
            EXPECT_EQ(e.to_object.c, ObjectColumns(object_map(inst.object_to_world, inst.world_to_object)).c);
            for (int r = 0; r < 3; ++r) {  // by columns: column 3 the origin, 0-2 the inverse's
                EXPECT_EQ(e.to_object.c[9 + r], inst.object_to_world.m[4 * r + 3]);
                for (int c = 0; c < 3; ++c) EXPECT_EQ(e.to_object.c[3 * c + r], inst.world_to_object.m[4 * r + c]);
            }
            EXPECT_EQ(e.identity, inst.identity);
            EXPECT_EQ(e.leaf, i);
            EXPECT_EQ(e.last, k + 1 == end) << "ref " << k;
        }
    }
    EXPECT_EQ(nodes_reached[0], 0);
    for (std::uint32_t w = 1; w < tlas.wide.node_count; ++w) EXPECT_EQ(nodes_reached[w], 1) << "wide node " << w;
}

/// Rays from random points of the field's cube in random directions, and from outside it at
/// instances' boxes.
std::vector<Ray> rays_through(const Tlas& tlas, std::uint32_t n, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::normal_distribution<float> g(0.0f, 1.0f);
    std::vector<Ray> rays;
    for (std::uint32_t i = 0; i < n; ++i) {
        if (i % 2) {
            rays.push_back({{-20 + 160 * u(rng), -20 + 160 * u(rng), -20 + 160 * u(rng)}, {g(rng), g(rng), g(rng)}});
            continue;
        }
        const Aabb& box = tlas.instances[rng() % tlas.instances.size()].world_box;
        const Vec3 target = box.lo + (box.hi - box.lo) * u(rng);
        const Vec3 origin{-30.0f, 160 * u(rng), 160 * u(rng)};
        rays.push_back({origin, target - origin});
    }
    return rays;
}

void expect_hits_of_the_binary_walk(const Field& f, std::uint32_t seed, std::uint32_t min_hits) {
    std::uint32_t hits = 0;
    for (const Ray& ray : rays_through(f.tlas, 3000, seed)) {
        std::uint32_t visited = 0;
        const InstanceHit wide = intersect_two_level(f.two_level, ray, Traversal::Wide, &visited);
        const InstanceHit binary = intersect_two_level(f.two_level, ray, Traversal::Stack);
        ASSERT_EQ(wide.instance, binary.instance);
        ASSERT_EQ(wide.hit.ref, binary.hit.ref);
        ASSERT_EQ(std::memcmp(&wide.hit.t, &binary.hit.t, sizeof(float)), 0);
        Ray limited = ray;  // the any-hit walk of the wide TLAS: exactly the hits before tmax
        limited.tmax = wide.hit.ref == kNoHit ? 50.0f : wide.hit.t;
        ASSERT_FALSE(occluded_two_level(f.two_level, limited, Traversal::Wide));
        if (wide.hit.ref == kNoHit) continue;
        limited.tmax = std::nextafter(wide.hit.t, kInfinity);
        ASSERT_TRUE(occluded_two_level(f.two_level, limited, Traversal::Wide));
        ++hits;
        ASSERT_EQ(std::memcmp(&wide.hit.u, &binary.hit.u, sizeof(float)), 0);
        ASSERT_EQ(std::memcmp(&wide.hit.v, &binary.hit.v, sizeof(float)), 0);
        EXPECT_GT(visited, 0u);
    }
    EXPECT_GT(hits, min_hits);
}

}  // namespace

TEST(TlasWide, IsTheBinaryTlasCollapsed) {
    for (std::uint32_t leaf_size : {1u, 4u}) {
        const Field f(700, leaf_size, 3);
        expect_wide_copy_of(f.tlas);
        EXPECT_LT(f.tlas.wide.node_count, f.tlas.tree.node_count() / 4);  // 8-wide: far fewer nodes
    }
    expect_wide_copy_of(Field(1, 1, 4).tlas);  // one leaf: the root's only child
}

TEST(TlasWide, WideWalkHitsAsTheBinaryWalk) {
    expect_hits_of_the_binary_walk(Field(700, 1, 5), 6, 150);
    expect_hits_of_the_binary_walk(Field(300, 4, 7), 8, 80);  // leaves of several instances
    expect_hits_of_the_binary_walk(Field(1, 1, 9), 10, 30);
}

TEST(TlasWide, AnEmptyTlasHasNoWideCopy) {
    const Field f(0, 1, 11);
    EXPECT_TRUE(f.tlas.tree.empty());
    EXPECT_EQ(f.tlas.wide.node_count, 0u);
    const InstanceHit h = intersect_two_level(f.two_level, {{0, 0, 0}, {1, 0, 0}}, Traversal::Wide);
    EXPECT_EQ(h.hit.ref, kNoHit);
}
