// The two-level walks' move of a ray into an instance's space (src/query/object_ray.h): four
// lanes by columns, bit for bit what ObjectMap's scalar rows give (transform.h), over random
// transforms and rays, rays starting next to the object's origin (p - P exact, Sterbenz), signed
// zeros, and scales from 2^-20 to 2^20; and its range test and rescaling, one pass over the bits,
// against coordinate_range.h's direction_in_range and scale_ray.
#include <gtest/gtest.h>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "bvhlab/transform.h"
#include "object_ray.h"

namespace bvhlab {
namespace {

bool same_bits(Vec3 a, Vec3 b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// A random rotation (axis and angle), scaled per axis by 2^[-20, 20] and sheared at random,
/// placed at `at`.
Transform random_transform(std::mt19937& rng, Vec3 at) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), angle(0.0f, 6.2831853f);
    std::uniform_int_distribution<int> e(-20, 20);
    Transform t;
    const float a = angle(rng), c = std::cos(a), s = std::sin(a);
    Vec3 k{u(rng), u(rng), u(rng)};
    const float n = std::sqrt(k.x * k.x + k.y * k.y + k.z * k.z) + 1e-6f;
    k = {k.x / n, k.y / n, k.z / n};
    const float r[9] = {c + k.x * k.x * (1 - c),       k.x * k.y * (1 - c) - k.z * s, k.x * k.z * (1 - c) + k.y * s,
                        k.y * k.x * (1 - c) + k.z * s, c + k.y * k.y * (1 - c),       k.y * k.z * (1 - c) - k.x * s,
                        k.z * k.x * (1 - c) - k.y * s, k.z * k.y * (1 - c) + k.x * s, c + k.z * k.z * (1 - c)};
    const float scale[3] = {std::ldexp(1.0f + 0.5f * u(rng), e(rng)), std::ldexp(1.0f + 0.5f * u(rng), e(rng)),
                            std::ldexp(1.0f + 0.5f * u(rng), e(rng))};
    for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 3; ++col) t.m[4 * row + col] = r[3 * row + col] * scale[col] + 0.1f * u(rng);
    t.m[3] = at.x, t.m[7] = at.y, t.m[11] = at.z;
    return t;
}

/// move_ray against ObjectMap::point and ::vector (rows, scalar).
void expect_same(const ObjectMap& map, const Ray& world) {
    Ray moved;
    move_ray(ObjectColumns(map), world, moved);
    EXPECT_TRUE(same_bits(moved.origin, map.point(world.origin)));
    EXPECT_TRUE(same_bits(moved.dir, map.vector(world.dir)));
}

TEST(ObjectRay, MoveRayIsTheScalarTransformBitForBit) {
    std::mt19937 rng(34);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::uniform_int_distribution<int> e(-30, 30), pick(0, 3);
    int tested = 0;
    for (int i = 0; i < 20000; ++i) {
        const float reach = std::ldexp(1.0f, e(rng));
        const Vec3 at{reach * u(rng), reach * u(rng), reach * u(rng)};
        const Transform t = random_transform(rng, at);
        if (!transform_invertible(t)) continue;
        const ObjectMap map = object_map(t, inverse(t));
        // an origin far away, near the object's origin (o - P exact), or on it
        const float near = std::ldexp(1.0f, e(rng));
        Vec3 o{reach * 4 * u(rng), reach * 4 * u(rng), reach * 4 * u(rng)};
        if (pick(rng) == 1) o = {at.x + near * u(rng), at.y + near * u(rng), at.z + near * u(rng)};
        if (pick(rng) == 2) o = at;
        Vec3 d{u(rng), u(rng), u(rng)};
        if (pick(rng) == 0) d.y = 0.0f, d.z = -0.0f;  // signed zeros through the products and sums
        expect_same(map, {o, d, 0.0f, 1e30f});
        ++tested;
    }
    EXPECT_GT(tested, 10000);  // most random transforms are invertible
}

TEST(ObjectRay, IdentityAndAxisAlignedKeepZerosSigns) {
    ObjectMap identity;
    for (float x : {0.0f, -0.0f, 1.0f, -3.5f})
        for (float y : {0.0f, -0.0f, 2.0f}) expect_same(identity, {{x, y, -0.0f}, {y, x, -0.0f}});
}

/// scale_in_range against direction_in_range then scale_ray, the two calls it replaces.
void expect_same_scaling(Vec3 d) {
    Ray a{{1, 2, 3}, d, 0.5f, 7.0f}, b = a;
    float t_scale = 0.0f;
    const bool in = scale_in_range(a, t_scale);
    ASSERT_EQ(in, direction_in_range(b.dir)) << d.x << " " << d.y << " " << d.z;
    if (!in) return;
    const float expected = scale_ray(b);
    EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0);
    EXPECT_EQ(t_scale, expected);
}

TEST(ObjectRay, ScaleInRangeIsTheRangeTestAndScaleRay) {
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    const float edges[] = {0.0f,    -0.0f,          1.0f,          -0.75f, 0x1p-80f, -0x1p-80f, 0x1.fffffep-81f,
                           0x1p80f, 0x1.000002p80f, -0x1p80f,      1e-40f, 3e38f,    inf,       -inf,
                           nan,     0.5f,           0x1.fffffep-1f};
    for (float x : edges)
        for (float y : edges)
            for (float z : edges) expect_same_scaling({x, y, z});
    std::mt19937 rng(35);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::uniform_int_distribution<int> e(-100, 100);
    for (int i = 0; i < 20000; ++i) {
        const float s = std::ldexp(1.0f, e(rng));
        expect_same_scaling({s * u(rng), s * u(rng), s * std::ldexp(u(rng), e(rng) / 4)});
    }
}

}  // namespace
}  // namespace bvhlab
