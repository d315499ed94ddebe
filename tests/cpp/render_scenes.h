// Scenes for the renderer tests (report §4.1's five spheres, a Whitted showcase, a bumpy mesh), and
// image comparison. A RenderTestScene owns everything its RenderScene borrows: keep it in place
// (make_* return unique_ptr).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "bvhlab/render.h"
#include "bvhlab/render_defaults.h"
#include "test_scenes.h"

namespace bvhlab::test {

struct RenderTestScene {
    Scene geometry;
    std::vector<float> materials;  // M×kMaterialFloats: r, g, b, reflective, transparent, ior, holdout, hidden
    std::vector<std::int32_t> triangle_material, sphere_material;
    Bvh bvh;
    RenderScene render;
    RenderSettings settings;

    std::int32_t material(Vec3 color, float reflective = 0, float transparent = 0, float ior = 1.5f,
                          bool holdout = false, std::uint32_t hidden = 0) {
        for (float v : {color.x, color.y, color.z, reflective, transparent, ior, holdout ? 1.0f : 0.0f, float(hidden)})
            materials.push_back(v);
        return std::int32_t(materials.size() / kMaterialFloats - 1);
    }
    void sphere(Vec3 center, float radius, std::int32_t m) {
        geometry.add_sphere(center, radius);
        sphere_material.push_back(m);
    }
    void triangle(Vec3 a, Vec3 b, Vec3 c, std::int32_t m) {
        geometry.add_triangle(a, b, c);
        triangle_material.push_back(m);
    }
    /// tiles×tiles squares on z = height over [-half, half]², alternating two materials.
    void checker_floor(float half, float height, int tiles, std::int32_t m0, std::int32_t m1) {
        const float step = 2 * half / float(tiles);
        for (int i = 0; i < tiles; ++i)
            for (int j = 0; j < tiles; ++j) {
                float x = -half + step * float(i), y = -half + step * float(j);
                std::int32_t m = (i + j) % 2 ? m1 : m0;
                triangle({x, y, height}, {x + step, y, height}, {x + step, y + step, height}, m);
                triangle({x, y, height}, {x + step, y + step, height}, {x, y + step, height}, m);
            }
    }
    void build(const BuildConfig& config = {}) {
        bvh = build_bvh(geometry.view(), config);
        MaterialView mv{materials.data(), materials.size() / kMaterialFloats, triangle_material.data(),
                        sphere_material.data()};
        render = make_render_scene(bvh, geometry.view(), mv);
    }
};

using ScenePtr = std::unique_ptr<RenderTestScene>;

inline void small_image(RenderSettings& s, std::uint32_t width = 64, std::uint32_t height = 48) {
    s.width = width;
    s.height = height;
}

/// Report §4.1 (Figure 3): five spheres in a row, here over a floor.
inline ScenePtr five_spheres() {
    auto s = std::make_unique<RenderTestScene>();
    const Vec3 colors[5] = {
        {0.9f, 0.2f, 0.2f}, {0.2f, 0.8f, 0.3f}, {0.2f, 0.4f, 0.9f}, {0.9f, 0.8f, 0.2f}, {0.7f, 0.3f, 0.8f}};
    for (int i = 0; i < 5; ++i) s->sphere({-4.0f + 2.0f * float(i), 0, 0.8f}, 0.8f, s->material(colors[i]));
    s->checker_floor(8, 0, 1, s->material({0.8f, 0.8f, 0.8f}), 0);
    s->build();
    s->settings.camera = look_at({0, -9, 4}, {0, 0, 0.8f}, {0, 0, 1}, 45);
    s->settings.light.position = {4, -6, 8};
    small_image(s->settings);
    return s;
}

/// Whitted's showcase (report §2.1): a glass sphere, a mirror sphere and a matte one over a checker
/// floor — refraction, reflection, and a shadow lightened by the glass.
inline ScenePtr whitted_showcase() {
    auto s = std::make_unique<RenderTestScene>();
    s->sphere({-1.1f, 0, 1}, 1, s->material({1, 1, 1}, 0.1f, 0.85f, 1.5f));
    s->sphere({1.3f, 1.2f, 1}, 1, s->material({0.9f, 0.9f, 0.9f}, 0.8f));
    s->sphere({0.2f, 3.5f, 0.7f}, 0.7f, s->material({0.9f, 0.3f, 0.2f}));
    s->sphere({2.8f, -1.0f, 0.5f}, 0.5f, s->material({0.3f, 0.5f, 0.9f}, 0, 0.5f, 1.0f));
    s->checker_floor(6, 0, 8, s->material({0.9f, 0.9f, 0.9f}), s->material({0.2f, 0.2f, 0.2f}, 0.2f));
    s->build();
    s->settings.camera = look_at({0, -7, 3}, {0, 0.5f, 0.8f}, {0, 0, 1}, 50);
    s->settings.light.position = {-3, -4, 7};
    s->settings.max_ray_depth = 6;
    s->settings.samples_per_axis = 2;
    small_image(s->settings);
    return s;
}

/// A bumpy height field of 2·n² triangles (n = 160: 51 200) over [-2, 2]², seen at a grazing angle.
inline ScenePtr bumpy_mesh(int n = 160) {
    auto s = std::make_unique<RenderTestScene>();
    const std::int32_t m = s->material({0.7f, 0.75f, 0.8f}, 0.15f);
    auto point = [n](int i, int j) {
        float x = -2 + 4 * float(i) / float(n), y = -2 + 4 * float(j) / float(n);
        return Vec3{x, y, 0.25f * std::sin(3 * x) * std::cos(2 * y) + 0.08f * std::sin(7 * x + 5 * y)};
    };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            s->triangle(point(i, j), point(i + 1, j), point(i + 1, j + 1), m);
            s->triangle(point(i, j), point(i + 1, j + 1), point(i, j + 1), m);
        }
    s->build();
    s->settings.camera = look_at({0.5f, -4.5f, 2.2f}, {0, 0, 0}, {0, 0, 1}, 45);
    s->settings.light.position = {3, -2, 4};
    small_image(s->settings);
    return s;
}

/// One matte sphere (radius 1 at the origin) seen along the diagonal of its box: the box corner
/// nearest the camera is in front of the sphere, the farthest exactly behind it (report §3.3).
inline ScenePtr overlay_sphere() {
    auto s = std::make_unique<RenderTestScene>();
    s->sphere({0, 0, 0}, 1, s->material({0.3f, 0.5f, 0.8f}));
    s->build();
    s->settings.camera = look_at({-4, -4, 4}, {0, 0, 0}, {0, 0, 1}, 45);
    s->settings.light.position = {-6, -2, 6};
    s->settings.overlay = true;
    s->settings.overlay_color_by_depth = false;  // one known line colour
    small_image(s->settings, 96, 72);
    return s;
}

/// Differences between two RGBA images, over the rgb channels.
struct ImageDiff {
    double mean_abs = 0;  ///< mean over all rgb values
    float max_abs = 0;
    double fraction_above = 0;  ///< of pixels with a channel differing by more than the threshold
};

inline ImageDiff compare_images(const std::vector<float>& a, const std::vector<float>& b, float threshold) {
    ImageDiff d;
    const std::size_t pixels = a.size() / 4;
    std::size_t above = 0;
    for (std::size_t p = 0; p < pixels; ++p) {
        float worst = 0;
        for (int c = 0; c < 3; ++c) {
            float e = std::fabs(a[4 * p + c] - b[4 * p + c]);
            if (!(e == e)) e = INFINITY;  // NaN on one side
            d.mean_abs += e;
            worst = std::max(worst, e);
        }
        d.max_abs = std::max(d.max_abs, worst);
        above += worst > threshold ? 1 : 0;
    }
    d.mean_abs /= double(3 * pixels);
    d.fraction_above = double(above) / double(pixels);
    return d;
}

}  // namespace bvhlab::test
