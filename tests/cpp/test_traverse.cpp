// Closest-hit traversal against brute force over every primitive, every traversal mode (the any-hit
// query: test_traverse_occluded.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <random>

#include "bvhlab/bvh.h"
#include "bvhlab/isa.h"
#include "bvhlab/render_settings.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"
#include "test_scenes.h"
#include "traverse_oracles.h"

using namespace bvhlab;
using test::brute_force;
using test::random_rays;
using test::supported_isas;

namespace {

void expect_same_hit(const Hit& got, const Hit& want) {
    ASSERT_EQ(got.t, want.t);      // the same float arithmetic on the same primitive
    ASSERT_EQ(got.ref, want.ref);  // ties go to the smaller reference in every traversal
    if (!(got.ref & gpu::REF_SPHERE_BIT)) {
        EXPECT_EQ(got.u, want.u);
        EXPECT_EQ(got.v, want.v);
    }
}

/// Every traversal, the wide one on every instruction set path, equals brute force.
void expect_same_hits(const Bvh& bvh, const std::vector<Ray>& rays) {
    const WideBvh wide = make_wide(bvh);
    const Isa before = active_isa();
    int hits = 0;
    for (const Ray& ray : rays) {
        Hit want = brute_force(bvh, ray);
        hits += want.ref != kNoHit;
        for (Traversal mode : {Traversal::Stack, Traversal::Stackless})
            expect_same_hit(intersect(bvh, ray, mode), want);
        std::uint32_t visited_first = 0;
        for (Isa isa : supported_isas()) {
            set_isa(isa);
            std::uint32_t visited = 0;
            expect_same_hit(intersect_wide(wide, bvh, ray, &visited), want);
            if (isa == Isa::Portable) visited_first = visited;
            EXPECT_EQ(visited, visited_first) << isa_name(isa);  // the same path through the tree
        }
        set_isa(before);
    }
    EXPECT_GT(hits, int(rays.size()) / 10) << "too few hits to test anything";
}

class EveryMethod : public ::testing::TestWithParam<SplitMethod> {};

TEST_P(EveryMethod, ClosestHitEqualsBruteForce) {
    auto scene = test::random_scene(3000, 400, 17);
    for (std::uint32_t leaf : {1u, 3u, 8u}) {
        BuildConfig cfg;
        cfg.method = GetParam();
        cfg.max_leaf_size = leaf;
        Bvh bvh = build_bvh(scene.view(), cfg);
        expect_same_hits(bvh, random_rays(3000, 5 + leaf));
    }
}

INSTANTIATE_TEST_SUITE_P(AllMethods, EveryMethod,
                         ::testing::Values(SplitMethod::Median, SplitMethod::Mean, SplitMethod::Midpoint,
                                           SplitMethod::Sah, SplitMethod::SweepSah, SplitMethod::Lbvh,
                                           SplitMethod::Sbvh),
                         [](const auto& info) { return to_string(info.param); });

TEST(Traverse, TminTmaxBoundTheHits) {
    test::Scene s;
    for (int i = 0; i < 10; ++i) s.add_triangle({-1, -1, float(i)}, {3, -1, float(i)}, {-1, 3, float(i)});
    Bvh bvh = build_bvh(s.view());
    for (Traversal mode : {Traversal::Stack, Traversal::Stackless}) {
        Hit h = intersect(bvh, {{0, 0, -5}, {0, 0, 1}, 7.5f, 100.0f}, mode);
        EXPECT_FLOAT_EQ(h.t, 8.0f);  // z = 3, the first plane past t = 7.5
        Hit none = intersect(bvh, {{0, 0, -5}, {0, 0, 1}, 0.0f, 4.5f}, mode);
        EXPECT_EQ(none.ref, kNoHit);
        EXPECT_EQ(none.t, kInfinity);
    }
}

// The packing (SIMD where available) against the rule written out: vertices copied bit for bit,
// the index and material in their words, and a triangle whose cross product is exactly zero
// collapsed to its first vertex. Includes the last triangle of the array (no read past it).
TEST(Packing, TrianglesAreCopiedAndZeroAreaOnesCollapsed) {
    auto scene = test::random_scene(64, 0, 5);
    for (int i = 0; i < 9; ++i) scene.triangles[9 * 10 + i] = float(i % 3);  // three equal vertices
    for (int c = 0; c < 3; ++c)  // collinear: v2 = 2 v1 - v0 (exact in float for these values)
        scene.triangles[9 * 63 + 3 + c] = 1.5f + c, scene.triangles[9 * 63 + c] = 1.0f + c,
                                     scene.triangles[9 * 63 + 6 + c] = 2.0f + c;
    const GeometryView g = scene.view();
    for (std::size_t i = 0; i < g.triangle_count; ++i) {
        const PackedPrim p = pack_triangle(g, i, 7);
        const float* v = g.triangles + 9 * i;
        const Vec3 v0{v[0], v[1], v[2]}, v1{v[3], v[4], v[5]}, v2{v[6], v[7], v[8]};
        const Vec3 e1 = v1 - v0, e2 = v2 - v0;
        const bool flat =
            e1.y * e2.z - e1.z * e2.y == 0.0f && e1.z * e2.x - e1.x * e2.z == 0.0f && e1.x * e2.y - e1.y * e2.x == 0.0f;
        EXPECT_EQ(flat, i == 10 || i == 63) << i;
        const Vec3 want[3] = {v0, flat ? v0 : v1, flat ? v0 : v2};
        const gpu::vec3 got[3] = {p.v0, p.v1, p.v2};
        for (int k = 0; k < 3; ++k)
            EXPECT_TRUE(got[k].x == want[k].x && got[k].y == want[k].y && got[k].z == want[k].z) << i << " " << k;
        EXPECT_EQ(p.ref, i);
        EXPECT_EQ(p.material, 7u);
        EXPECT_EQ(p.unused, 0u);
    }
}

TEST(Traverse, DegenerateTrianglesAreNeverHit) {
    test::Scene s;
    s.add_triangle({0, 0, 0}, {1, 1, 1}, {2, 2, 2});                    // collinear
    s.add_triangle({0, 0, 0}, {0, 0, 0}, {1, 0, 0});                    // repeated vertex
    s.add_triangle({0.5f, 0.5f, 0}, {0.5f, 0.5f, 0}, {0.5f, 0.5f, 0});  // a point
    Bvh bvh = build_bvh(s.view());
    for (const Ray& r : random_rays(2000, 3)) EXPECT_EQ(intersect(bvh, r, Traversal::Stack).ref, kNoHit);
    EXPECT_EQ(intersect(bvh, {{0.5f, 0.5f, -1}, {0, 0, 1}}, Traversal::Stack).ref, kNoHit);
    EXPECT_EQ(intersect(bvh, {{1, 1, 5}, {0, 0, -1}}, Traversal::Stackless).ref, kNoHit);
}

/// Every traversal on one ray: stack, stackless and wide.
std::vector<Hit> all_traversals(const Bvh& bvh, const WideBvh& wide, const Ray& ray) {
    return {intersect(bvh, ray, Traversal::Stack), intersect(bvh, ray, Traversal::Stackless),
            intersect_wide(wide, bvh, ray)};
}

TEST(Traverse, RaysFarFromATinyTriangleNeverHitIt) {
    // A triangle 1.8e-5 across at the origin beside a large one, rays from 100-500 units away (a
    // helper's audit): relative to such an origin the tiny triangle's vertices are nearly one
    // vector, and two of its edge functions' products rounded to equal floats, two zeros that passed
    // the sign test: 1,070 of 200,000 rays "hit" it at points hundreds of units from it, on every
    // traversal. Zero edge functions are made again exactly now (geometry.glsl exact_edge).
    const float s = 1.7864242e-05f;
    test::Scene scene;
    scene.add_triangle({s, 0, 0}, {s, s, 0}, {s, 0, s});
    scene.add_triangle({1000, 1000, 1000}, {1000, 1000, 0}, {0, 0, 1000});
    Bvh bvh = build_bvh(scene.view(), BuildConfig{});
    std::vector<Ray> rays{{{284.92874f, 222.90292f, 260.5462f}, {1.1115526f, -1.2859659f, 1.163311f}}};
    std::mt19937 rng(0);
    std::uniform_real_distribution<float> at(100.0f, 500.0f);
    std::normal_distribution<float> g(0.0f, 1.0f);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    while (rays.size() < 20000) {
        const Vec3 o{at(rng), at(rng), at(rng)};
        if (rays.size() % 2) {  // at random, as the audit's
            rays.push_back({o, {g(rng), g(rng), g(rng)}});
        } else {  // toward a point of the large triangle (hits, for expect_same_hits to compare)
            const float a = unit(rng), b = unit(rng) * (1.0f - a);
            const Vec3 p = Vec3{1000, 1000, 1000} * (1.0f - a - b) + Vec3{1000, 1000, 0} * a + Vec3{0, 0, 1000} * b;
            rays.push_back({o, p - o});
        }
    }
    int near_tiny = 0;
    for (const Ray& ray : rays) {
        const Hit hit = brute_force(bvh, ray);
        if (hit.ref != 0) continue;  // the tiny triangle is primitive 0
        // where it is hit, in double: within a hair of it (0.01 units; its own size is 1.8e-5)
        const double x = double(ray.origin.x) + double(hit.t) * ray.dir.x,
                     y = double(ray.origin.y) + double(hit.t) * ray.dir.y,
                     z = double(ray.origin.z) + double(hit.t) * ray.dir.z;
        EXPECT_LT(std::sqrt((x - s) * (x - s) + y * y + z * z), 0.01) << "a hit far from the tiny triangle";
        ++near_tiny;
    }
    EXPECT_LT(near_tiny, 5);  // a ray at random passes within 0.01 of it hardly ever
    expect_same_hits(bvh, rays);
}

TEST(Traverse, RaysOnBoxFacesAndEdgesHit) {
    // The unit square as two triangles: rays straight down on its edges, x = 1 and y = 1 included,
    // lie in the root box's faces (a zero direction component on a slab plane) and must hit.
    test::Scene s;
    s.add_triangle({0, 0, 0}, {1, 0, 0}, {1, 1, 0});
    s.add_triangle({0, 0, 0}, {1, 1, 0}, {0, 1, 0});
    for (std::uint32_t leaf : {1u, 2u}) {
        BuildConfig c;
        c.max_leaf_size = leaf;
        Bvh bvh = build_bvh(s.view(), c);
        WideBvh wide = make_wide(bvh);
        for (float x : {0.0f, 0.25f, 0.5f, 1.0f})
            for (float y : {0.0f, 0.5f, 0.75f, 1.0f})
                for (Vec3 d : {Vec3{0, 0, -1}, Vec3{-0.0f, -0.0f, -2.0f}}) {
                    Ray ray{{x, y, 1}, d};
                    for (const Hit& h : all_traversals(bvh, wide, ray)) {
                        EXPECT_NE(h.ref, kNoHit) << "x " << x << " y " << y << " leaf " << leaf;
                        EXPECT_EQ(h.t, 1.0f / std::fabs(d.z));
                    }
                }
        // just outside the faces: misses
        for (Vec3 o : {Vec3{1.0001f, 0.5f, 1}, Vec3{0.5f, -0.0001f, 1}})
            for (const Hit& h : all_traversals(bvh, wide, {o, {0, 0, -1}})) EXPECT_EQ(h.ref, kNoHit);
    }
}

/// Möller–Trumbore in float, as the traversals had it before the watertight test: only to show
/// that the rays below are hard (it lets some of them through the mesh).
bool moller_trumbore_hits(const Vec3& v0, const Vec3& v1, const Vec3& v2, const Ray& r) {
    const Vec3 e1 = v1 - v0, e2 = v2 - v0, p = cross(r.dir, e2), s = r.origin - v0, q = cross(s, e1);
    const float det = dot(e1, p);
    if (det == 0.0f) return false;
    const float u = dot(s, p) / det, v = dot(r.dir, q) / det;
    return u >= 0.0f && v >= 0.0f && u + v <= 1.0f && dot(e2, q) / det > 0.0f;
}

/// Rays from inside a closed mesh straight at its vertices and at points of its edges, and rays
/// in the planes that hold its edges: every one must hit, on every traversal (watertight: Woop,
/// Benthin and Wald 2013). Möller–Trumbore lets some of these rays through (checked below).
TEST(Traverse, RaysThroughSharedEdgesAndVerticesOfAClosedMeshNeverMiss) {
    const test::Scene mesh = test::octasphere(12, {0.25f, -0.5f, 3.0f}, 2.0f);
    std::vector<Ray> rays;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> f(0.0f, 1.0f);
    const Vec3 origins[] = {{0.25f, -0.5f, 3.0f}, {0.75f, -0.125f, 2.5f}, {-0.5f, -1.0f, 4.0f}};
    for (const Vec3& o : origins)
        for (std::size_t t = 0; t < mesh.triangles.size() / 9; ++t) {
            const float* v = &mesh.triangles[9 * t];
            const Vec3 a{v[0], v[1], v[2]}, b{v[3], v[4], v[5]}, c{v[6], v[7], v[8]};
            rays.push_back({o, a - o});                     // through a vertex
            rays.push_back({o, (a + b) * 0.5f - o});        // an edge's midpoint
            rays.push_back({o, a + (c - a) * f(rng) - o});  // a point of an edge
        }
    for (int i = -40; i <= 40; ++i)  // in the planes x = 0.25, y = -0.5, z = 3 that hold edges
        for (Vec3 d : {Vec3{0, float(i) / 40.0f, 1}, Vec3{float(i) / 40.0f, 0, -1}, Vec3{float(i) / 40.0f, 1, 0}})
            rays.push_back({origins[0], d});
    for (std::uint32_t leaf : {1u, 4u}) {
        BuildConfig cfg;
        cfg.max_leaf_size = leaf;
        const Bvh bvh = build_bvh(mesh.view(), cfg);
        const WideBvh wide = make_wide(bvh);
        const Isa before = active_isa();
        for (const Ray& ray : rays) {
            for (const Hit& h : all_traversals(bvh, wide, ray)) ASSERT_NE(h.ref, kNoHit) << "leaf " << leaf;
            for (Isa isa : supported_isas()) {
                set_isa(isa);
                ASSERT_NE(intersect_wide(wide, bvh, ray).ref, kNoHit) << isa_name(isa);
            }
            set_isa(before);
        }
        expect_same_hits(bvh, rays);
    }
    std::size_t leaks = 0;
    for (const Ray& ray : rays) {
        bool hit = false;
        for (std::size_t t = 0; t < mesh.triangles.size() / 9 && !hit; ++t) {
            const float* v = &mesh.triangles[9 * t];
            hit = moller_trumbore_hits({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], v[7], v[8]}, ray);
        }
        leaks += !hit;
    }
    EXPECT_GT(leaks, 0u) << "no ray here would leak through Möller–Trumbore: the test tests nothing";
    std::printf("Möller–Trumbore lets %zu of these %zu rays through the mesh\n", leaks, rays.size());
}

TEST(Traverse, TiesGoToTheSmallestReferenceInEveryTraversal) {
    // Forty copies of one triangle and a sphere touching its plane: every ray through the overlap
    // hits them all at the same distance; all traversals must report triangle 0.
    test::Scene s;
    test::Scene scattered = test::random_scene(200, 0, 4);
    s.triangles = scattered.triangles;
    for (int i = 0; i < 40; ++i) s.add_triangle({20, 20, 5}, {24, 20, 5}, {20, 24, 5});
    s.add_sphere({21, 21, 4}, 1.0f);  // top at z = 5, under the copies
    for (std::uint32_t leaf : {1u, 4u})
        for (SplitMethod m : {SplitMethod::Sah, SplitMethod::Median, SplitMethod::Lbvh}) {
            BuildConfig c;
            c.method = m, c.max_leaf_size = leaf;
            Bvh bvh = build_bvh(s.view(), c);
            WideBvh wide = make_wide(bvh);
            for (float x : {20.5f, 21.0f, 22.0f})
                for (const Hit& h : all_traversals(bvh, wide, {{x, 21, 10}, {0, 0, -1}})) {
                    EXPECT_EQ(h.ref, 200u) << to_string(m) << " leaf " << leaf << " x " << x;  // the first copy
                    EXPECT_EQ(h.t, 5.0f);
                }
        }
}

TEST(Traverse, EmptyTreeMisses) {
    test::Scene s;
    Bvh bvh = build_bvh(s.view());
    Hit h = intersect(bvh, {{0, 0, 0}, {1, 0, 0}}, Traversal::Stackless);
    EXPECT_EQ(h.ref, kNoHit);
    EXPECT_EQ(h.t, kInfinity);
    EXPECT_EQ(intersect_wide(make_wide(bvh), bvh, {{0, 0, 0}, {1, 0, 0}}).ref, kNoHit);
}

TEST(Traverse, WideTreeOfOneLeafAndOfFewChildren) {
    for (int n : {1, 2, 3, 5}) {
        test::Scene s;
        for (int i = 0; i < n; ++i) s.add_sphere({float(3 * i), 0, 0}, 1.0f);
        BuildConfig c;
        c.max_leaf_size = 4;
        c.traversal_cost = 100;  // everything that fits one leaf is one leaf
        Bvh bvh = build_bvh(s.view(), c);
        WideBvh wide = make_wide(bvh);
        for (int i = 0; i < n; ++i) {
            Hit h = intersect_wide(wide, bvh, {{float(3 * i), 0, -5}, {0, 0, 1}});
            EXPECT_EQ(h.ref, gpu::REF_SPHERE_BIT | std::uint32_t(i)) << n << " spheres";
            EXPECT_FLOAT_EQ(h.t, 4.0f);
        }
        EXPECT_EQ(intersect_wide(wide, bvh, {{1.5f, 0, -5}, {0, 0, 1}}).ref, kNoHit);
    }
}

TEST(Traverse, SphereFromInsideHitsTheFarSide) {
    test::Scene s;
    s.add_sphere({0, 0, 0}, 2.0f);
    Bvh bvh = build_bvh(s.view());
    Hit h = intersect(bvh, {{0, 0, 0}, {1, 0, 0}}, Traversal::Stack);
    EXPECT_FLOAT_EQ(h.t, 2.0f);
    EXPECT_EQ(h.ref, gpu::REF_SPHERE_BIT | 0u);
    EXPECT_NEAR(h.u, 0.5f, 1e-6);  // longitude 0
    EXPECT_NEAR(h.v, 0.5f, 1e-6);  // on the equator
}

TEST(Traverse, BatchAgreesWithSingleRaysOnAnyThreadCount) {
    auto scene = test::random_scene(2000, 100, 23);
    Bvh bvh = build_bvh(scene.view());
    auto rays = random_rays(5000, 77);
    std::vector<float> o, d;
    for (const Ray& r : rays)
        o.insert(o.end(), {r.origin.x, r.origin.y, r.origin.z}), d.insert(d.end(), {r.dir.x, r.dir.y, r.dir.z});
    for (std::uint32_t threads : {1u, 2u, 5u}) {
        std::vector<float> t(rays.size()), u(rays.size()), v(rays.size());
        std::vector<std::int32_t> prim(rays.size());
        std::vector<std::uint8_t> kind(rays.size());
        intersect_batch(bvh, {o.data(), d.data(), rays.size()},
                        {t.data(), prim.data(), kind.data(), u.data(), v.data()}, Traversal::Stackless, threads);
        for (std::size_t i = 0; i < rays.size(); ++i) {
            Hit h = intersect(bvh, rays[i], Traversal::Stack);
            ASSERT_EQ(t[i], h.t);
            ASSERT_EQ(prim[i], h.ref == kNoHit ? -1 : std::int32_t(h.ref & gpu::REF_INDEX_MASK));
            ASSERT_EQ(kind[i], h.ref != kNoHit && (h.ref & gpu::REF_SPHERE_BIT) ? 1 : 0);
        }
    }
}

}  // namespace
