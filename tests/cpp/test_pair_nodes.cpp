// The stack walk's node format (pair_nodes.h): each internal node with its children's boxes, checked
// against the depth-first tree it came from by walking both together; and the renderers' refusal of
// a render scene whose pairs are not its tree's. The images the tracer makes
// with it are checked against the stackless walk, which reads the depth-first nodes, in
// test_vulkan.cpp and tests/python/test_render_cpu.py.
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/pair_nodes.h"
#include "bvhlab/render.h"
#include "test_scenes.h"

using namespace bvhlab;

namespace {

bool same_box(const gpu::vec3& lo, const gpu::vec3& hi, const BvhNode& n) {
    return lo.x == n.lo.x && lo.y == n.lo.y && lo.z == n.lo.z && hi.x == n.hi.x && hi.y == n.hi.y && hi.z == n.hi.z;
}

/// Walks pair `p` and node `i` together: the same boxes and leaf ranges, pairs met in the order
/// 0, 1, 2, ... (depth-first), leaves met in the order of their ranges.
struct PairWalk {
    const Bvh& bvh;
    const BigVector<gpu::BvhPair>& pairs;
    std::uint32_t next_pair = 0, next_slot = 0;

    void child(std::uint32_t word, std::uint32_t count, const gpu::vec3& lo, const gpu::vec3& hi, std::uint32_t node) {
        const BvhNode& n = bvh.nodes[node];
        ASSERT_TRUE(same_box(lo, hi, n)) << "node " << node;
        if (is_leaf(n)) {
            ASSERT_EQ(word, gpu::PAIR_LEAF_BIT | n.index) << "node " << node;
            ASSERT_EQ(count, leaf_count(n));
            ASSERT_EQ(n.index, next_slot);
            next_slot += count;
        } else {
            ASSERT_EQ(count, 0u);
            ASSERT_EQ(word & gpu::PAIR_LEAF_BIT, 0u);
            visit(word, node);
        }
    }

    void visit(std::uint32_t p, std::uint32_t i) {
        ASSERT_EQ(p, next_pair++);
        ASSERT_LT(p, pairs.size());
        const gpu::BvhPair& pair = pairs[p];
        child(pair.child_a, pair.count_a, pair.lo_a, pair.hi_a, i + 1);
        child(pair.child_b, pair.count_b, pair.lo_b, pair.hi_b, bvh.nodes[i].index);
    }
};

void expect_same_tree(const Bvh& bvh) {
    BigVector<gpu::BvhPair> pairs = make_pair_nodes(bvh);
    std::uint32_t internal = 0;
    for (const BvhNode& n : bvh.nodes) internal += is_leaf(n) ? 0 : 1;
    ASSERT_EQ(pairs.size(), internal);
    if (internal == 0) return;
    PairWalk walk{bvh, pairs};
    walk.visit(0, 0);
    EXPECT_EQ(walk.next_pair, internal) << "every pair reached once";
    EXPECT_EQ(walk.next_slot, bvh.refs.size()) << "the leaves cover every reference";
}

}  // namespace

TEST(PairNodes, EveryMethodAndLeafSizeGiveTheSameTree) {
    test::Scene scene = test::random_scene(20000, 500, 7);
    for (SplitMethod method : {SplitMethod::Median, SplitMethod::Mean, SplitMethod::Midpoint, SplitMethod::Sah,
                               SplitMethod::SweepSah, SplitMethod::Lbvh, SplitMethod::Sbvh})
        for (std::uint32_t leaf : {1u, 4u, 16u}) {
            BuildConfig config;
            config.method = method;
            config.max_leaf_size = leaf;
            SCOPED_TRACE(testing::Message() << "method " << int(method) << ", leaf " << leaf);
            expect_same_tree(build_bvh(scene.view(), config));
        }
}

TEST(PairNodes, EmptyTreeAndARootLeafHaveNoPairs) {
    EXPECT_TRUE(make_pair_nodes(Bvh{}).empty());
    test::Scene one;
    one.add_sphere({0, 0, 0}, 1);
    one.add_triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    BuildConfig config;
    config.method = SplitMethod::Median;  // a leaf wherever the count fits
    config.max_leaf_size = 8;
    Bvh leaf = build_bvh(one.view(), config);
    ASSERT_EQ(leaf.node_count(), 1u);
    EXPECT_TRUE(make_pair_nodes(leaf).empty());
    config.max_leaf_size = 1;
    expect_same_tree(build_bvh(one.view(), config));  // a root of two leaves: one pair
}

TEST(PairNodes, NodesThatAreNotADepthFirstTreeAreAnError) {
    test::Scene scene = test::random_scene(500, 0, 3);
    BuildConfig config;
    config.max_leaf_size = 1;
    Bvh bvh = build_bvh(scene.view(), config);
    ASSERT_GT(bvh.node_count(), 3u);
    Bvh moved = bvh;
    moved.nodes[0].index += 1;  // the root's second child is not where its first child's subtree ends
    EXPECT_THROW(make_pair_nodes(moved), std::invalid_argument);
    Bvh cut = bvh;
    cut.nodes.pop_back();  // the last leaf missing
    EXPECT_THROW(make_pair_nodes(cut), std::invalid_argument);
    Bvh open = bvh;
    open.nodes.back() = open.nodes[0];  // the last node internal: more internal nodes than a full tree has
    EXPECT_THROW(make_pair_nodes(open), std::invalid_argument);
    Bvh far = bvh;
    std::uint32_t leaf = 1;
    while (!is_leaf(far.nodes[leaf])) ++leaf;
    far.nodes[leaf].index |= gpu::PAIR_LEAF_BIT;  // a leaf whose first slot needs bit 31
    EXPECT_THROW(make_pair_nodes(far), std::invalid_argument);
}

TEST(PairNodes, ARenderSceneLeftBehindByARefitOrWithoutPairsIsAnError) {
    test::Scene scene = test::random_scene(2000, 50, 5);
    Bvh bvh = build_bvh(scene.view());
    RenderScene rs = make_render_scene(bvh, scene.view(), {});
    RenderSettings settings;
    settings.width = 8, settings.height = 8;
    std::vector<float> image(8 * 8 * 4);
    EXPECT_NO_THROW(render_cpu(rs, settings, {image.data()}, 1));
    for (float& v : scene.triangles) v += 0.5f;  // the geometry moves; the tree is refitted in place
    refit(bvh, scene.view());
    EXPECT_THROW(render_cpu(rs, settings, {image.data()}, 1), std::invalid_argument);
    RenderScene again = make_render_scene(bvh, scene.view(), {});
    EXPECT_NO_THROW(render_cpu(again, settings, {image.data()}, 1));
    again.pairs.clear();  // as a scene put together by hand, without make_render_scene
    EXPECT_THROW(render_cpu(again, settings, {image.data()}, 1), std::invalid_argument);
}
