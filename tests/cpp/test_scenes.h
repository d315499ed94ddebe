// Scenes for the C++ tests: deterministic random triangles and spheres, and hard cases.
#pragma once
#include <cstdint>
#include <random>
#include <vector>

#include "bvhlab/geometry.h"

namespace bvhlab::test {

/// Owns the arrays a GeometryView borrows.
struct Scene {
    std::vector<float> triangles;  // T×9
    std::vector<float> spheres;    // S×4
    GeometryView view() const {
        return {triangles.data(), triangles.size() / 9, spheres.data(), spheres.size() / 4};
    }
    void add_triangle(Vec3 a, Vec3 b, Vec3 c) {
        for (Vec3 v : {a, b, c}) triangles.insert(triangles.end(), {v.x, v.y, v.z});
    }
    void add_sphere(Vec3 c, float r) { spheres.insert(spheres.end(), {c.x, c.y, c.z, r}); }
};

/// Small triangles and spheres scattered in a cube of side 10, clustered around a few centres so
/// that split methods disagree.
inline Scene random_scene(std::uint32_t triangles, std::uint32_t spheres, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::normal_distribution<float> g(0.0f, 1.0f);
    Vec3 centres[4] = {{1, 1, 1}, {8, 2, 5}, {5, 8, 8}, {2, 7, 3}};
    auto point = [&] {
        Vec3 c = centres[rng() % 4];
        return u(rng) < 0.5f ? Vec3{10 * u(rng), 10 * u(rng), 10 * u(rng)} : c + Vec3{g(rng), g(rng), g(rng)};
    };
    Scene s;
    for (std::uint32_t i = 0; i < triangles; ++i) {
        Vec3 p = point();
        float size = 0.05f + 0.5f * u(rng) * u(rng);
        auto jitter = [&] { return Vec3{g(rng), g(rng), g(rng)} * size; };
        s.add_triangle(p + jitter(), p + jitter(), p + jitter());
    }
    for (std::uint32_t i = 0; i < spheres; ++i) s.add_sphere(point(), 0.05f + 0.3f * u(rng));
    return s;
}

}  // namespace bvhlab::test
