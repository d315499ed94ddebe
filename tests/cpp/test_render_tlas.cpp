// The CPU reference tracer walks two-level trees (issue 34): an instanced scene (rotation,
// non-uniform scale, mirroring, many instances of one mesh) renders as the same triangles moved
// into the world as one flat mesh, and a scene of one identity instance renders exactly as the flat
// scene, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "bvhlab/tlas.h"
#include "render_scenes.h"
#include "transforms.h"

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

/// Two meshes (a glass-like octasphere, a matte triangle cloud) placed by instances, and the same
/// triangles moved into the world as one flat scene: a mirrored instance's triangles reversed, so
/// that its outside stays out (the tracer's inverse-transpose normals keep it so).
struct InstancedRender {
    std::vector<Scene> meshes;
    std::vector<std::vector<std::int32_t>> mesh_materials;
    std::vector<Bvh> trees;
    std::vector<std::uint32_t> blas_of;
    std::vector<Transform> transforms;
    std::vector<float> materials{0.8f, 0.8f, 0.8f, 0.2f, 0.4f, 1.3f,  // glass-like: refraction sees the normals
                                 0.9f, 0.3f, 0.2f, 0.0f, 0.0f, 1.0f};
    RenderTestScene flat;
    Tlas tlas;
    RenderScene two_level;
    RenderSettings settings;

    void add_mesh(Scene mesh, std::int32_t material) {
        mesh_materials.emplace_back(mesh.view().triangle_count, material);
        meshes.push_back(std::move(mesh));
    }

    void finish() {
        flat.materials = materials;
        for (std::size_t i = 0; i < blas_of.size(); ++i) {
            const GeometryView g = meshes[blas_of[i]].view();
            const Transform& t = transforms[i];
            const auto& m = t.m;
            const double det = double(m[0]) * (double(m[5]) * m[10] - double(m[6]) * m[9]) -
                               double(m[1]) * (double(m[4]) * m[10] - double(m[6]) * m[8]) +
                               double(m[2]) * (double(m[4]) * m[9] - double(m[5]) * m[8]);
            for (std::uint32_t p = 0; p < g.triangle_count; ++p) {
                const Vec3 a = t.point(g.vertex(p, 0)), b = t.point(g.vertex(p, 1)), c = t.point(g.vertex(p, 2));
                if (det < 0) flat.triangle(a, c, b, mesh_materials[blas_of[i]][p]);
                else flat.triangle(a, b, c, mesh_materials[blas_of[i]][p]);
            }
        }
        flat.build();
        for (const Scene& m : meshes) trees.push_back(build_bvh(m.view()));
        std::vector<const Bvh*> blases;
        std::vector<RenderMesh> render_meshes;
        for (std::size_t k = 0; k < trees.size(); ++k) {
            blases.push_back(&trees[k]);
            render_meshes.push_back({&trees[k], meshes[k].view(), mesh_materials[k].data(), nullptr});
        }
        tlas = build_tlas(blases, blas_of, transforms);
        two_level = make_render_scene(tlas, render_meshes, {materials.data(), materials.size() / 6, nullptr, nullptr});
        settings.camera = look_at({9, -6, 12}, {9, 8, 0}, {0, 0, 1}, 60);
        settings.light.position = {20, -10, 40};
        settings.max_ray_depth = 4;
        small_image(settings, 96, 72);
    }
};

InstancedRender mixed_instances() {
    InstancedRender s;
    s.add_mesh(octasphere(4, {0, 0, 0}, 2.0f), 0);
    s.add_mesh(random_scene(300, 0, 2), 1);
    const float pi = 3.14159265f;
    s.blas_of = {0, 1, 0, 0, 1, 0};
    s.transforms = {
        Transform{},
        make_transform({0, 0, 1}, pi / 5, {3, 3, 3}, {8, 0, 0}),
        make_transform({1, 2, 3}, 1.1f, {2.0f, 0.5f, 1.3f}, {0, 10, 2}),     // non-uniform scale
        make_transform({1, 0, 0}, 0.3f, {-1, 1, 1}, {8, 10, 0}),             // mirrored
        make_transform({0, 1, 0}, 2.0f, {-0.7f, -1.5f, 2.5f}, {16, 6, 1}),   // mirrored, non-uniform
        make_transform({1, 1, 0}, 0.7f, {1.5f, 0.6f, 1.0f}, {16, 14, -1}),  // non-uniform
    };
    s.finish();
    return s;
}

InstancedRender many_instances() {
    InstancedRender s;
    s.add_mesh(octasphere(3, {0, 0, 0}, 1.0f), 0);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int x = 0; x < 10; ++x)
        for (int y = 0; y < 10; ++y) {
            const Vec3 scale{0.4f + 0.6f * u(rng), 0.4f + 0.6f * u(rng), (u(rng) < 0.3f ? -1.0f : 1.0f) * (0.4f + u(rng))};
            s.blas_of.push_back(0);
            s.transforms.push_back(make_transform({u(rng), u(rng), 1}, 6 * u(rng), scale, {2.0f * x, 2.0f * y, 0}));
        }
    s.finish();
    return s;
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
    const InstancedRender s = mixed_instances();
    ASSERT_TRUE(s.two_level.two_level());
    expect_same_image(s, Traversal::Stack);
    expect_same_image(s, Traversal::Stackless);
}

TEST(RenderTwoLevel, ManyInstancesOfOneMesh) {
    const InstancedRender s = many_instances();
    expect_same_image(s, Traversal::Stack);
    expect_same_image(s, Traversal::Stackless);
}

TEST(RenderTwoLevel, OneIdentityInstanceIsTheFlatSceneBitForBit) {
    const ScenePtr flat = whitted_showcase();
    const Tlas tlas = build_tlas({&flat->bvh}, {0}, {Transform{}});
    const RenderScene one = make_render_scene(
        tlas, {{&flat->bvh, flat->geometry.view(), flat->triangle_material.data(), flat->sphere_material.data()}},
        {flat->materials.data(), flat->materials.size() / 6, nullptr, nullptr});
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
    InstancedRender s = mixed_instances();
    std::vector<RenderMesh> one_mesh{{&s.trees[0], s.meshes[0].view(), s.mesh_materials[0].data(), nullptr}};
    const MaterialView mv{s.materials.data(), s.materials.size() / 6, nullptr, nullptr};
    EXPECT_THROW(make_render_scene(s.tlas, one_mesh, mv), std::invalid_argument);
    std::vector<RenderMesh> swapped{{&s.trees[1], s.meshes[0].view(), nullptr, nullptr},
                                    {&s.trees[0], s.meshes[1].view(), nullptr, nullptr}};
    EXPECT_THROW(make_render_scene(s.tlas, swapped, mv), std::invalid_argument);
}
