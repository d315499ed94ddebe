// The CPU reference tracer walks two-level trees (issue 34): an instanced scene (rotation,
// non-uniform scale, mirroring, many instances of one mesh) renders as the same triangles moved
// into the world as one flat mesh, and a scene of one identity instance renders exactly as the flat
// scene, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "instanced_render.h"

using namespace bvhlab;
using namespace bvhlab::test;

namespace {

struct Images {
    std::vector<float> color, depth;
};

Images render(const RenderScene& scene, const RenderSettings& settings) {
    Images out{std::vector<float>(4ull * settings.width * settings.height),
               std::vector<float>(std::size_t(settings.width) * settings.height)};
    render_cpu(scene, settings, {out.color.data(), out.depth.data(), nullptr, nullptr}, 2);
    return out;
}

double depth_mismatch(const Images& a, const Images& b) {
    std::size_t off = 0;
    for (std::size_t i = 0; i < a.depth.size(); ++i)
        off += std::fabs(a.depth[i] - b.depth[i]) > 1e-4f * std::fabs(b.depth[i]) + 1e-5f ? 1 : 0;
    return double(off) / double(a.depth.size());
}

void expect_same_image(const InstancedRender& s, Traversal traversal) {
    RenderSettings settings = s.settings;
    settings.traversal = traversal;
    const Images a = render(s.two_level, settings), b = render(s.flat.render, settings);
    std::size_t hits = 0;
    for (float d : a.depth) hits += d < kNoDepth ? 1 : 0;
    EXPECT_GT(double(hits) / double(a.depth.size()), 0.1);  // the scene is in view
    EXPECT_LE(depth_mismatch(a, b), 0.01);
    EXPECT_LE(compare_images(a.color, b.color, 2e-3f).fraction_above, 0.01);
}

}  // namespace

TEST(RenderTwoLevel, InstancesRenderAsTheFlattenedScene) {
    const InstancedPtr p = mixed_instances();
    const InstancedRender& s = *p;
    ASSERT_TRUE(s.two_level.two_level());
    expect_same_image(s, Traversal::Stack);
    expect_same_image(s, Traversal::Stackless);
}

TEST(RenderTwoLevel, ManyInstancesOfOneMesh) {
    const InstancedPtr p = many_instances();
    const InstancedRender& s = *p;
    expect_same_image(s, Traversal::Stack);
    expect_same_image(s, Traversal::Stackless);
}

TEST(RenderTwoLevel, OneIdentityInstanceIsTheFlatSceneBitForBit) {
    const ScenePtr flat = whitted_showcase();
    const Tlas tlas = build_tlas({&flat->bvh}, {0}, {Transform{}});
    const RenderScene one = make_render_scene(
        tlas, {{&flat->bvh, flat->geometry.view(), flat->triangle_material.data(), flat->sphere_material.data()}},
        {flat->materials.data(), flat->materials.size() / kMaterialFloats, nullptr, nullptr});
    EXPECT_FALSE(one.two_level());
    for (Traversal t : {Traversal::Stack, Traversal::Stackless}) {
        RenderSettings settings = flat->settings;
        settings.traversal = t;
        const Images a = render(one, settings), b = render(flat->render, settings);
        EXPECT_EQ(a.color, b.color);
        EXPECT_EQ(a.depth, b.depth);
    }
}

TEST(RenderTwoLevel, RefusesMeshesThatAreNotTheTlas) {
    InstancedPtr p = mixed_instances();
    InstancedRender& s = *p;
    std::vector<RenderMesh> one_mesh{{&s.trees[0], s.meshes[0].view(), s.mesh_materials[0].data(), nullptr}};
    const MaterialView mv{s.materials.data(), s.materials.size() / kMaterialFloats, nullptr, nullptr};
    EXPECT_THROW(make_render_scene(s.tlas, one_mesh, mv), std::invalid_argument);
    std::vector<RenderMesh> swapped{{&s.trees[1], s.meshes[0].view(), nullptr, nullptr},
                                    {&s.trees[0], s.meshes[1].view(), nullptr, nullptr}};
    EXPECT_THROW(make_render_scene(s.tlas, swapped, mv), std::invalid_argument);
}
