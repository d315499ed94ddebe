// instanced_render.h — two-level render scenes for the tracer tests (test_render_tlas, test_vulkan):
// meshes placed by instances (rotation, non-uniform scale, mirroring, many of one mesh) and the
// same triangles moved into the world as one flat scene.
#pragma once
#include <memory>
#include <random>
#include <vector>

#include "bvhlab/tlas.h"
#include "render_scenes.h"
#include "transforms.h"

namespace bvhlab::test {

/// Two meshes (a glass-like octasphere, a matte triangle cloud) placed by instances, and the same
/// triangles moved into the world as one flat scene: a mirrored instance's triangles reversed, so
/// that its outside stays out (the tracer's inverse-transpose normals keep it so).
struct InstancedRender {
    std::vector<Scene> meshes;
    std::vector<std::vector<std::int32_t>> mesh_materials;
    std::vector<Bvh> trees;
    std::vector<std::uint32_t> blas_of;
    std::vector<Transform> transforms;
    std::vector<float> materials{
        0.8f, 0.8f, 0.8f, 0.2f, 0.4f, 1.3f, 0.0f, 0.0f,  // glass-like: refraction sees the normals
        0.9f, 0.3f, 0.2f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f};
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
        two_level = make_render_scene(tlas, render_meshes,
                                      {materials.data(), materials.size() / kMaterialFloats, nullptr, nullptr});
        settings.camera = look_at({9, -6, 12}, {9, 8, 0}, {0, 0, 1}, 60);
        settings.light.position = {20, -10, 40};
        settings.max_ray_depth = 4;
        small_image(settings, 96, 72);
    }
};

/// Owned in place: the flat scene's RenderScene borrows its tree.
using InstancedPtr = std::unique_ptr<InstancedRender>;

inline InstancedPtr mixed_instances() {
    auto p = std::make_unique<InstancedRender>();
    InstancedRender& s = *p;
    s.add_mesh(octasphere(4, {0, 0, 0}, 2.0f), 0);
    s.add_mesh(random_scene(300, 0, 2), 1);
    const float pi = 3.14159265f;
    s.blas_of = {0, 1, 0, 0, 1, 0};
    s.transforms = {
        Transform{},
        make_transform({0, 0, 1}, pi / 5, {3, 3, 3}, {8, 0, 0}),
        make_transform({1, 2, 3}, 1.1f, {2.0f, 0.5f, 1.3f}, {0, 10, 2}),    // non-uniform scale
        make_transform({1, 0, 0}, 0.3f, {-1, 1, 1}, {8, 10, 0}),            // mirrored
        make_transform({0, 1, 0}, 2.0f, {-0.7f, -1.5f, 2.5f}, {16, 6, 1}),  // mirrored, non-uniform
        make_transform({1, 1, 0}, 0.7f, {1.5f, 0.6f, 1.0f}, {16, 14, -1}),  // non-uniform
    };
    s.finish();
    return p;
}

inline InstancedPtr many_instances() {
    auto p = std::make_unique<InstancedRender>();
    InstancedRender& s = *p;
    s.add_mesh(octasphere(3, {0, 0, 0}, 1.0f), 0);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int x = 0; x < 10; ++x)
        for (int y = 0; y < 10; ++y) {
            const Vec3 scale{0.4f + 0.6f * u(rng), 0.4f + 0.6f * u(rng),
                             (u(rng) < 0.3f ? -1.0f : 1.0f) * (0.4f + u(rng))};
            s.blas_of.push_back(0);
            s.transforms.push_back(make_transform({u(rng), u(rng), 1}, 6 * u(rng), scale, {2.0f * x, 2.0f * y, 0}));
        }
    s.finish();
    return p;
}

}  // namespace bvhlab::test
