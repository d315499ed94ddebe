// The fingerprint of an updated tree (bvh.h Bvh::fingerprint): a refit leaves it to be read back
// from the tree's packed primitives when first asked. It must equal geometry_fingerprint of the
// geometry the tree was updated for (an independent pass over the input) after every policy,
// whatever happens to the input after the update, with triangles of zero area among the moved
// ones, on copies and on threads reading it at once; and a render scene must still refuse a tree
// that does not match its geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <thread>
#include <vector>

#include "bvhlab/render.h"
#include "bvhlab/update.h"
#include "test_scenes.h"

using namespace bvhlab;
using namespace bvhlab::test;

namespace {

/// `scene` with every primitive moved by its own small offset (the topology's costs grow).
Scene moved(const Scene& scene, float amount) {
    Scene out = scene;
    for (std::size_t i = 0; i < out.triangles.size(); ++i) out.triangles[i] += amount * std::sin(float(i / 9) * 0.37f);
    for (std::size_t i = 0; i < out.spheres.size(); i += 4) out.spheres[i + 1] += amount * std::cos(float(i));
    return out;
}

/// Every policy but rebuild, adaptive with its top rebuilt on any growth.
std::vector<UpdateConfig> refitting_policies() {
    std::vector<UpdateConfig> out(4);
    out[0].policy = UpdatePolicy::Refit, out[1].policy = UpdatePolicy::Partial;
    out[1].min_subtree_primitives = 16;
    out[2].policy = UpdatePolicy::Adaptive;
    out[3].policy = UpdatePolicy::Adaptive;
    out[3].target_growth = out[3].top_growth = 1.0f, out[3].tree_growth = 100.0f, out[3].min_subtree_primitives = 16;
    return out;
}

}  // namespace

TEST(UpdateFingerprint, EqualsTheInputsAfterEveryPolicyThoughTheInputChangesAfter) {
    const Scene scene = random_scene(6000, 30, 4);
    const Bvh tree = build_bvh(scene.view());
    const NodeCostArray built = subtree_costs(tree);
    for (const UpdateConfig& c : refitting_policies()) {
        SCOPED_TRACE(to_string(c.policy));
        Scene input = moved(scene, 0.8f);
        const std::uint64_t expected = geometry_fingerprint(input.view());
        NodeCostArray built_out;
        UpdateStats stats;
        const Bvh t = update_bvh(tree, built, input.view(), c, built_out, &stats);
        input.triangles[9 * 17 + 4] += 1.0f, input.spheres[2] -= 1.0f;  // the caller's arrays change after
        EXPECT_EQ(t.fingerprint(), expected);
        EXPECT_NE(t.fingerprint(), geometry_fingerprint(input.view()));
        EXPECT_EQ(Bvh(t).fingerprint(), expected);  // a copy keeps it
    }
}

TEST(UpdateFingerprint, TrianglesOfZeroAreaKeepItExact) {
    // packed as a point, such a triangle's other two corners are not in the tree: its fingerprint
    // must come from the input, and a change to those corners alone must still change it
    Scene scene = random_scene(3000, 0, 8);
    for (std::size_t t : {5u, 900u, 2999u})
        for (int k = 0; k < 3; ++k) scene.triangles[9 * t + 3 + k] = scene.triangles[9 * t + k];  // two corners one
    const Bvh tree = build_bvh(scene.view());
    const NodeCostArray built = subtree_costs(tree);
    const Scene other = moved(scene, 0.5f);  // each triangle moved whole: the two corners stay one
    Scene stretched = other;                 // triangle 900's third corner moved: still zero area
    stretched.triangles[9 * 900 + 6] += 0.25f;
    for (const UpdateConfig& c : refitting_policies()) {
        SCOPED_TRACE(to_string(c.policy));
        NodeCostArray out_a, out_b;
        const Bvh a = update_bvh(tree, built, other.view(), c, out_a);
        const Bvh b = update_bvh(tree, built, stretched.view(), c, out_b);
        EXPECT_EQ(a.fingerprint(), geometry_fingerprint(other.view()));
        EXPECT_EQ(b.fingerprint(), geometry_fingerprint(stretched.view()));
        EXPECT_NE(a.fingerprint(), b.fingerprint());
    }
}

TEST(UpdateFingerprint, ThreadsReadingItAtOnceGetTheSameValue) {
    const Scene scene = random_scene(40000, 100, 6);
    const Bvh tree = build_bvh(scene.view());
    const Scene input = moved(scene, 0.3f);
    const Bvh t = refitted(tree, input.view());
    const std::uint64_t expected = geometry_fingerprint(input.view());
    std::vector<std::uint64_t> seen(4);
    std::vector<std::thread> readers;
    for (std::size_t k = 0; k < seen.size(); ++k) readers.emplace_back([&, k] { seen[k] = t.fingerprint(); });
    for (std::thread& r : readers) r.join();
    for (std::uint64_t v : seen) EXPECT_EQ(v, expected);
}

TEST(UpdateFingerprint, ARenderSceneStillRefusesAStaleTree) {
    const Scene scene = random_scene(5000, 20, 2);
    const Bvh tree = build_bvh(scene.view());
    const NodeCostArray built = subtree_costs(tree);
    const Scene input = moved(scene, 0.6f);
    for (const UpdateConfig& c : refitting_policies()) {
        SCOPED_TRACE(to_string(c.policy));
        NodeCostArray built_out;
        Bvh t = update_bvh(tree, built, input.view(), c, built_out);
        EXPECT_THROW(make_render_scene(t, scene.view(), MaterialView{}), std::invalid_argument);  // the old geometry
        const RenderScene rs = make_render_scene(t, input.view(), MaterialView{});
        EXPECT_NO_THROW(check_render_scene(rs));
        t = refitted(t, moved(input, 0.2f).view());  // the tree changed under the render scene
        EXPECT_THROW(check_render_scene(rs), std::invalid_argument);
    }
}
