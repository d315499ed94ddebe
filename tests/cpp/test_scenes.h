// Scenes for the C++ tests: deterministic random triangles and spheres, and hard cases.
#pragma once
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "bvhlab/geometry.h"

namespace bvhlab::test {

/// Owns the arrays a GeometryView borrows.
struct Scene {
    std::vector<float> triangles;  // T×9
    std::vector<float> spheres;    // S×4
    GeometryView view() const { return {triangles.data(), triangles.size() / 9, spheres.data(), spheres.size() / 4}; }
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

/// A closed mesh: the octahedron with vertices ±x, ±y, ±z (radius r around `c`), each face cut
/// into level² triangles and its vertices pushed onto the sphere. A vertex is computed from the
/// same numbers in every face that shares it, so shared vertices are equal; the octahedron's edges
/// stay in the planes x, y, z = c, so rays in those planes run along edges. Triangles wind outwards.
inline Scene octasphere(int level, Vec3 c = {}, float r = 1.0f) {
    auto on_sphere = [&](Vec3 p) { return c + p * (r / std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z)); };
    Scene s;
    for (int face = 0; face < 8; ++face) {
        const Vec3 a{face & 1 ? -1.0f : 1.0f, 0, 0}, b{0, face & 2 ? -1.0f : 1.0f, 0}, z{0, 0, face & 4 ? -1.0f : 1.0f};
        const bool flip = ((face & 1) ^ ((face >> 1) & 1) ^ ((face >> 2) & 1)) != 0;
        auto vertex = [&](int i, int j) {  // barycentric (level - i - j, i, j) of z, a, b, exact on the edges
            const float n = float(level), fa = float(i) / n, fb = float(j) / n, fz = float(level - i - j) / n;
            return on_sphere(Vec3{a.x * fa, b.y * fb, z.z * fz});
        };
        auto add = [&](Vec3 p, Vec3 q, Vec3 t) { flip ? s.add_triangle(p, t, q) : s.add_triangle(p, q, t); };
        for (int i = 0; i < level; ++i)
            for (int j = 0; i + j < level; ++j) {
                add(vertex(i, j), vertex(i + 1, j), vertex(i, j + 1));
                if (i + j + 1 < level) add(vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j + 1));
            }
    }
    return s;
}

}  // namespace bvhlab::test
