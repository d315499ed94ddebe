// Instance transforms (transform.h, coordinate_range.h, tlas.h): bad instances are refused by name,
// the inverse undoes a transform, boxes moved through a transform are the box-by-box union bit for
// bit, and a ray's scaling by a power of two is frexp and ldexp's bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "bvhlab/coordinate_range.h"
#include "bvhlab/tlas.h"
#include "bvhlab/transform.h"
#include "test_scenes.h"
#include "traverse_oracles.h"
#include "transforms.h"

using namespace bvhlab;
using namespace bvhlab::test;

namespace {
void expect_refused(const std::vector<std::uint32_t>& blas_of, const std::vector<Transform>& transforms,
                    const std::string& words) {
    const Scene mesh = random_scene(50, 0, 3);
    const Bvh tree = build_bvh(mesh.view());
    try {
        build_tlas({&tree}, blas_of, transforms);
        ADD_FAILURE() << "accepted: " << words;
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
}
}  // namespace

TEST(Tlas, BadInstancesAreRefusedByName) {
    Transform nan, zero_axis, flat_axes, far;
    nan.m[5] = std::nanf("");
    zero_axis.m[10] = 0.0f;                         // scale z by 0
    flat_axes.m[1] = 1.0f, flat_axes.m[5] = 1e-9f;  // columns 0 and 1 (nearly) parallel
    far.m[3] = 0x1p41f;                             // moved beyond the coordinate range
    expect_refused({0, 3}, {Transform{}, Transform{}}, "instance 1 refers to mesh 3, but the scene has 1 mesh");
    expect_refused({0, 0}, {Transform{}, nan}, "instance 1: the transform has a NaN");
    expect_refused({0}, {zero_axis}, "instance 0: the transform cannot be inverted (an axis of length 0");
    expect_refused({0}, {flat_axes}, "instance 0: the transform cannot be inverted (a zero-scale axis, or axes");
    expect_refused({0}, {far}, "instance 0 would place mesh 0 outside");
    expect_refused({0, 0}, {Transform{}}, "one transform per instance");
}

/// Scales as small as 2^-75 and as large as 2^20 (transform.h, kMaxTransformEntry): an instance
/// scaled by a power of two s is hit as the unscaled mesh is hit by the ray whose origin is divided
/// by s (every step exact: the same primitive, t times s bit for bit), on the binary walks; scales
/// of 2^-77 and 2^77 (1e-25 used to be accepted, and then every ray missed) are refused by name.
TEST(Tlas, TinyAndLargeScalesAreHitExactlyOrRefused) {
    const Scene mesh = random_scene(4000, 0, 5);
    const Bvh tree = build_bvh(mesh.view());
    for (int e : {-75, -40, -1, 20}) {
        const float s = std::ldexp(1.0f, e);
        Transform t;
        t.m[0] = t.m[5] = t.m[10] = s;
        const Tlas tlas = build_tlas({&tree}, {0}, {t});
        const TwoLevel scene{&tlas, {{&tree, nullptr}}};
        std::uint32_t hits = 0;
        for (const Ray& flat_ray : random_rays(1000, 41)) {
            const Ray world{flat_ray.origin * s, flat_ray.dir};
            for (Traversal mode : {Traversal::Stack, Traversal::Stackless}) {
                const Hit flat = intersect(tree, flat_ray, mode);
                const InstanceHit two = intersect_two_level(scene, world, mode);
                ASSERT_EQ(two.hit.ref, flat.ref) << "scale 2^" << e;
                if (flat.ref == kNoHit) continue;
                ASSERT_EQ(two.hit.t, flat.t * s) << "scale 2^" << e;
                hits += mode == Traversal::Stack;
            }
        }
        EXPECT_GT(hits, 100u) << "scale 2^" << e;
    }
    for (int e : {-77, 77, -100}) {  // one axis only: the determinant's test, relative, passes these
        Transform t;
        t.m[0] = std::ldexp(1.0f, e);
        expect_refused({0}, {t}, "instance 0: the transform scales by more than 2^76");
    }
}

TEST(Tlas, InverseUndoesTheTransform) {
    const Transform t = make_transform({1, 2, 3}, 1.1f, {2.0f, -0.5f, 1.3f}, {-14, 3, 2});
    const Transform inv = inverse(t);
    for (Vec3 p : {Vec3{1, 2, 3}, Vec3{-5, 0.25f, 9}}) {
        const Vec3 back = inv.point(t.point(p));
        EXPECT_NEAR(back.x, p.x, 1e-5f);
        EXPECT_NEAR(back.y, p.y, 1e-5f);
        EXPECT_NEAR(back.z, p.z, 1e-5f);
    }
}

/// transform_boxes over boxes made ready once (BoxesToMove: two boxes at a time, the matrix in
/// double once) and rounded out by bits rather than nextafterf: the same box, bit for bit, as the
/// box-by-box computation, over transforms and boxes with zeros of both signs, empty boxes, odd
/// counts and magnitudes from 2^-30 to 2^30.
TEST(Tlas, MovedBoxesAreTheBoxByBoxUnionBitForBit) {
    auto box_by_box = [](const Transform& t, const Aabb* boxes, std::size_t count) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (std::size_t k = 0; k < count; ++k) {
            const Aabb& b = boxes[k];
            if (b.empty()) continue;
            const double c[3] = {0.5 * (double(b.lo.x) + b.hi.x), 0.5 * (double(b.lo.y) + b.hi.y),
                                 0.5 * (double(b.lo.z) + b.hi.z)};
            const double h[3] = {0.5 * (double(b.hi.x) - b.lo.x), 0.5 * (double(b.hi.y) - b.lo.y),
                                 0.5 * (double(b.hi.z) - b.lo.z)};
            for (int r = 0; r < 3; ++r) {
                const double m0 = t.m[4 * r], m1 = t.m[4 * r + 1], m2 = t.m[4 * r + 2];
                const double centre = m0 * c[0] + m1 * c[1] + m2 * c[2] + t.m[4 * r + 3];
                const double half = std::fabs(m0) * h[0] + std::fabs(m1) * h[1] + std::fabs(m2) * h[2];
                lo[r] = std::min(lo[r], centre - half), hi[r] = std::max(hi[r], centre + half);
            }
        }
        Aabb out;
        if (lo[0] > hi[0]) return out;
        for (int r = 0; r < 3; ++r) {
            const double pad = 0x1p-20 * std::max({std::fabs(lo[r]), std::fabs(hi[r]), hi[r] - lo[r]});
            out.lo[r] = std::nextafter(float(lo[r] - pad), -INFINITY);
            out.hi[r] = std::nextafter(float(hi[r] + pad), INFINITY);
        }
        return out;
    };
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> mantissa(-2.0f, 2.0f);
    std::uniform_int_distribution<int> exponent(-30, 30), kind(0, 5);
    auto value = [&](int e) { return kind(rng) == 0 ? 0.0f : kind(rng) == 0 ? -0.0f : std::ldexp(mantissa(rng), e); };
    for (int i = 0; i < 50000; ++i) {
        Transform t;
        for (float& x : t.m) x = value(exponent(rng) / 3);
        Aabb boxes[9];
        const std::size_t count = std::size_t(i % 10);
        for (std::size_t k = 0; k < count; ++k) {
            const int e = exponent(rng);
            const Vec3 a{value(e), value(e), value(e)}, b{value(e), value(e), value(e)};
            boxes[k].lo = min(a, b), boxes[k].hi = max(a, b);
            if (i % 7 == 0 && k == 0) boxes[k] = Aabb{};
        }
        const Aabb expected = box_by_box(t, boxes, count);
        const Aabb got = transform_boxes(t, BoxesToMove(boxes, count));
        ASSERT_EQ(std::memcmp(&got, &expected, sizeof got), 0) << "case " << i;
    }
    const Transform zero{{0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}};  // a point at the origin: ±denorm_min
    const Aabb origin{{0, 0, 0}, {0, 0, 0}};
    const Aabb got = transform_boxes(zero, &origin, 1), expected = box_by_box(zero, &origin, 1);
    EXPECT_EQ(std::memcmp(&got, &expected, sizeof got), 0);
}

/// scale_ray takes its power of two from the largest component's exponent bits (no frexp, ldexp):
/// the same ray, bit for bit, as frexp and ldexp give, over the whole range of directions, and
/// tmin, tmax of every kind (0, inf, subnormal results).
TEST(Tlas, ScaleRayIsFrexpAndLdexpBitForBit) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> mantissa(-1.0f, 1.0f);
    std::uniform_int_distribution<int> exponent(-80, 79);
    const float tmaxes[] = {kInfinity, 0.0f, 1.0f, 3.0e38f, 1e-38f, 7.0f};
    auto bits = [](float f) {
        std::uint32_t b;
        std::memcpy(&b, &f, sizeof b);
        return b;
    };
    for (int i = 0; i < 20000; ++i) {
        const int e = exponent(rng);
        Ray ray{{0, 0, 0}, {std::ldexp(mantissa(rng), e), std::ldexp(mantissa(rng), e), std::ldexp(mantissa(rng), e)}};
        if (!direction_in_range(ray.dir)) continue;
        ray.tmin = i % 3 ? 0.0f : std::ldexp(mantissa(rng) + 1.0f, exponent(rng));
        ray.tmax = tmaxes[i % 6];
        Ray expected = ray;
        int k;
        std::frexp(largest_component(ray.dir), &k);
        const float expected_scale = k ? std::ldexp(1.0f, -k) : 1.0f;
        if (k) {
            expected.dir = ray.dir * std::ldexp(1.0f, -k);
            expected.tmin = std::ldexp(ray.tmin, k), expected.tmax = std::ldexp(ray.tmax, k);
        }
        const float scale = scale_ray(ray);
        ASSERT_EQ(bits(scale), bits(expected_scale));
        ASSERT_EQ(bits(ray.dir.x), bits(expected.dir.x));
        ASSERT_EQ(bits(ray.dir.y), bits(expected.dir.y));
        ASSERT_EQ(bits(ray.dir.z), bits(expected.dir.z));
        ASSERT_EQ(bits(ray.tmin), bits(expected.tmin));
        ASSERT_EQ(bits(ray.tmax), bits(expected.tmax));
    }
}
