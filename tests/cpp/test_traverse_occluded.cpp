// The any-hit query (occluded) on a single tree: equal to the closest hit's t < tmax on every
// traversal and instruction set path, for single rays and batches; empty trees, empty ranges and
// bad tmax.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

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

/// The tmax values each ray is asked with, from its closest hit's t (inf on a miss): no limit, the
/// hit's t exactly (not occluded: a hit counts only before tmax, as in intersect), the next float
/// after it (occluded), halfway, and a random one.
std::vector<float> tmax_cases(float t_closest, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 20.0f);
    std::vector<float> out{kInfinity, u(rng), 0.0f};
    if (t_closest != kInfinity)
        out.insert(out.end(), {t_closest, std::nextafter(t_closest, kInfinity), std::nextafter(t_closest, 0.0f),
                               0.5f * t_closest});
    return out;
}

/// occluded on every traversal (the wide one on every instruction set path) equals the closest
/// hit's t < tmax for every ray and every tmax of tmax_cases; returns how many were occluded.
std::uint32_t expect_occluded_is_closest_before_tmax(const Bvh& bvh, const std::vector<Ray>& rays, std::uint32_t seed) {
    const WideBvh wide = make_wide(bvh);
    const Isa before = active_isa();
    std::mt19937 rng(seed);
    std::uint32_t occluded_count = 0, wrong = 0;
    for (Ray ray : rays) {
        ray.tmax = kInfinity;
        const float t_closest = brute_force(bvh, ray).t;
        for (float tmax : tmax_cases(t_closest, rng)) {
            ray.tmax = tmax;
            const bool want = t_closest < tmax;
            occluded_count += want;
            auto check = [&](bool got, const std::string& what) {
                if (got != want && ++wrong <= 5)
                    ADD_FAILURE() << what << ": tmax " << tmax << " closest t " << t_closest;
            };
            for (Traversal mode : {Traversal::Stack, Traversal::Stackless})
                check(occluded(bvh, ray, mode), to_string(mode));
            for (Isa isa : supported_isas()) {
                set_isa(isa);
                check(occluded_wide(wide, ray), "wide " + std::string(isa_name(isa)));
            }
            set_isa(before);
        }
    }
    return occluded_count;
}

TEST(Occluded, EqualsClosestHitBeforeTmaxOnRandomScenes) {
    for (std::uint32_t seed : {3u, 8u}) {
        const auto scene = test::random_scene(2500, 300, seed);
        for (std::uint32_t leaf : {1u, 4u, 8u})
            for (SplitMethod m : {SplitMethod::Sah, SplitMethod::Lbvh}) {
                BuildConfig cfg;
                cfg.method = m, cfg.max_leaf_size = leaf;
                const Bvh bvh = build_bvh(scene.view(), cfg);
                auto rays = random_rays(1500, seed + leaf);
                std::mt19937 rng(seed);
                std::uniform_real_distribution<float> u(0.0f, 3.0f);
                for (std::size_t i = 0; i < rays.size(); i += 3) rays[i].tmin = u(rng);  // tmin bounds it too
                const std::uint32_t n = expect_occluded_is_closest_before_tmax(bvh, rays, seed);
                EXPECT_GT(n, rays.size() / 4) << "too few occluded rays to test anything";
            }
    }
}

/// Rays through a closed mesh's shared vertices and edges and in the planes of its edges (the
/// watertight test's hard cases, as in RaysThroughSharedEdgesAndVerticesOfAClosedMeshNeverMiss).
TEST(Occluded, EqualsClosestHitBeforeTmaxOnRaysGrazingEdgesAndVertices) {
    const test::Scene mesh = test::octasphere(10, {0.25f, -0.5f, 3.0f}, 2.0f);
    std::vector<Ray> rays;
    const Vec3 inside{0.25f, -0.5f, 3.0f}, outside{-3.0f, 2.0f, 6.5f};
    for (const Vec3& o : {inside, outside})
        for (std::size_t t = 0; t < mesh.triangles.size() / 9; ++t) {
            const float* v = &mesh.triangles[9 * t];
            const Vec3 a{v[0], v[1], v[2]}, b{v[3], v[4], v[5]};
            rays.push_back({o, a - o});               // through a vertex
            rays.push_back({o, (a + b) * 0.5f - o});  // an edge's midpoint
        }
    for (int i = -30; i <= 30; ++i)
        for (Vec3 d : {Vec3{0, float(i) / 30.0f, 1}, Vec3{float(i) / 30.0f, 0, -1}}) rays.push_back({inside, d});
    for (std::uint32_t leaf : {1u, 4u}) {
        BuildConfig cfg;
        cfg.max_leaf_size = leaf;
        const Bvh bvh = build_bvh(mesh.view(), cfg);
        EXPECT_GT(expect_occluded_is_closest_before_tmax(bvh, rays, leaf), rays.size());
    }
}

/// Shadow rays as a renderer casts them (the case the wide any-hit walk's farthest-first order is
/// for: design.md, "Where repeat1m's shadow rays lose"): from points on a row of closed meshes,
/// each backed off its surface along the ray that found it, to a light above the row's middle,
/// tmax the light's distance, so that the walk pushes leaves and nodes of many meshes and goes
/// from the light's end. Single rays on every path and the batch, against the brute force.
TEST(Occluded, ShadowRaysFromARowOfMeshesToALightEqualTheBruteForce) {
    test::Scene row;
    for (int k = 0; k < 12; ++k) {
        const test::Scene mesh = test::octasphere(6, {3.0f * float(k), 0.0f, 0.0f}, 1.2f);
        row.triangles.insert(row.triangles.end(), mesh.triangles.begin(), mesh.triangles.end());
    }
    const Bvh bvh = build_bvh(row.view());
    const WideBvh wide = make_wide(bvh);
    const Vec3 light{16.5f, 0.3f, 0.6f};
    std::vector<Ray> shadow;
    for (Ray r : random_rays(3000, 17)) {  // from random rays' hits on the row
        r.origin = {33.0f * r.origin.x / 10.0f - 0.5f, 3.0f * r.origin.y / 10.0f - 1.5f,
                    3.0f * r.origin.z / 10.0f - 1.5f};
        const float t = brute_force(bvh, r).t;
        if (t == kInfinity) continue;
        const Vec3 at = r.origin + r.dir * (t * 0.9999f), to = light - at;
        const float dist = std::sqrt(to.x * to.x + to.y * to.y + to.z * to.z);
        shadow.push_back({at, to * (1.0f / dist), 0.0f, dist});
    }
    ASSERT_GT(shadow.size(), 500u);
    std::uint32_t wrong = 0, occluded_count = 0;
    const Isa before = active_isa();
    for (const Ray& r : shadow) {
        Ray open = r;
        open.tmax = kInfinity;
        const bool want = brute_force(bvh, open).t < r.tmax;
        occluded_count += want;
        for (Isa isa : supported_isas()) {
            set_isa(isa);
            if (occluded_wide(wide, r) != want && ++wrong <= 5) ADD_FAILURE() << "wide " << isa_name(isa);
        }
    }
    set_isa(before);
    EXPECT_GT(occluded_count, shadow.size() / 4);
    EXPECT_LT(occluded_count + 5, shadow.size()) << "too few lit points to test a whole walk";
    std::vector<float> o, d, tmax;
    for (const Ray& r : shadow) {
        o.insert(o.end(), {r.origin.x, r.origin.y, r.origin.z}), d.insert(d.end(), {r.dir.x, r.dir.y, r.dir.z});
        tmax.push_back(r.tmax);
    }
    RayBatch batch{o.data(), d.data(), shadow.size()};
    batch.tmax_of = tmax.data();
    for (Isa isa : supported_isas()) {
        set_isa(isa);
        std::unique_ptr<bool[]> got(new bool[shadow.size()]);
        occluded_batch(bvh, batch, got.get(), Traversal::Wide, 2, &wide);
        for (std::size_t i = 0; i < shadow.size(); ++i) {
            Ray open = shadow[i];
            open.tmax = kInfinity;
            ASSERT_EQ(got[i], brute_force(bvh, open).t < shadow[i].tmax) << i << " " << isa_name(isa);
        }
    }
    set_isa(before);
}

TEST(Occluded, EmptyTreeAndZeroOrNegativeRangesAreNeverOccluded) {
    test::Scene empty;
    const Bvh none = build_bvh(empty.view());
    EXPECT_FALSE(occluded(none, {{0, 0, 0}, {1, 0, 0}}, Traversal::Stack));
    EXPECT_FALSE(occluded_wide(make_wide(none), {{0, 0, 0}, {1, 0, 0}}));
    test::Scene s;
    s.add_triangle({-1, -1, 2}, {3, -1, 2}, {-1, 3, 2});
    const Bvh bvh = build_bvh(s.view());
    const WideBvh wide = make_wide(bvh);
    for (float tmax : {0.0f, -1.0f, 2.0f}) {  // the hit at t = 2 is not before tmax = 2
        const Ray ray{{0, 0, 0}, {0, 0, 1}, 0.0f, tmax};
        EXPECT_FALSE(occluded(bvh, ray, Traversal::Stackless)) << tmax;
        EXPECT_FALSE(occluded_wide(wide, ray)) << tmax;
    }
    EXPECT_TRUE(occluded(bvh, {{0, 0, 0}, {0, 0, 1}, 0.0f, 2.0001f}, Traversal::Stack));
    // a tree of one leaf: the wide root is a node with the leaf its only child, tested at once
    EXPECT_TRUE(occluded_wide(wide, {{0, 0, 0}, {0, 0, 1}, 0.0f, 2.0001f}));
    EXPECT_FALSE(occluded(bvh, {{0, 0, 0}, {0, 0, 1}, 2.0f, 5.0f}, Traversal::Stack));  // nor at exactly tmin
}

TEST(Occluded, BatchAgreesWithSingleRaysOnAnyThreadCountWithPerRayTmax) {
    const auto scene = test::random_scene(2000, 100, 29);
    const Bvh bvh = build_bvh(scene.view());
    const WideBvh wide = make_wide(bvh);
    const auto rays = random_rays(6000, 31);
    std::vector<float> o, d, tmax;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.0f, 15.0f);
    for (const Ray& r : rays) {
        o.insert(o.end(), {r.origin.x, r.origin.y, r.origin.z}), d.insert(d.end(), {r.dir.x, r.dir.y, r.dir.z});
        tmax.push_back(u(rng));
    }
    RayBatch batch{o.data(), d.data(), rays.size()};
    batch.tmax_of = tmax.data();
    for (Traversal mode : {Traversal::Stack, Traversal::Stackless, Traversal::Wide})
        for (std::uint32_t threads : {1u, 2u, 5u}) {
            std::unique_ptr<bool[]> got(new bool[rays.size()]);
            occluded_batch(bvh, batch, got.get(), mode, threads, &wide);
            for (std::size_t i = 0; i < rays.size(); ++i) {
                Ray r = rays[i];
                r.tmax = tmax[i];
                ASSERT_EQ(got[i], occluded(bvh, r, Traversal::Stack)) << i;
            }
        }
}

TEST(Occluded, BatchRefusesNanAndNegativeTmax) {
    const auto scene = test::random_scene(100, 0, 2);
    const Bvh bvh = build_bvh(scene.view());
    const float o[6] = {0, 0, 0, 1, 1, 1}, d[6] = {1, 0, 0, 0, 1, 0};
    bool out[2];
    auto refused = [&](RayBatch b, const char* words) {
        try {
            occluded_batch(bvh, b, out, Traversal::Stack);
            ADD_FAILURE() << "accepted: " << words;
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
        }
    };
    refused({o, d, 2, 0.0f, -1.0f}, "tmax must be a number >= 0");
    refused({o, d, 2, 0.0f, std::nanf("")}, "tmax must be a number >= 0");
    const float per_ray[2] = {1.0f, std::nanf("")};
    refused({o, d, 2, 0.0f, kInfinity, per_ray}, "ray 1: tmax must be a number >= 0");
    const float negative[2] = {-0.5f, 1.0f};
    refused({o, d, 2, 0.0f, kInfinity, negative}, "ray 0: tmax");
}

// A negative tmin was answered, wrongly: the box test widens a box's far side by scaling its
// distance (ray.h hit_box), which narrows it where the distance is negative, so a triangle behind
// the origin in a box flat on an axis was missed. Refused by every batch query, with its value.
TEST(Occluded, BatchesRefuseNanAndNegativeTmin) {
    const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const Bvh bvh = build_bvh(GeometryView{tri, 1});
    const WideBvh wide = make_wide(bvh);
    const float o[3] = {0.2f, 0.2f, 1.0f}, d[3] = {0, 0, 1};
    float t, u, v;
    std::int32_t prim;
    std::uint8_t kind;
    bool out;
    for (const float tmin : {-10.0f, -1e-30f, std::nanf("")}) {
        const RayBatch rays{o, d, 1, tmin, kInfinity};
        for (const Traversal mode : {Traversal::Stack, Traversal::Stackless, Traversal::Wide}) {
            try {
                intersect_batch(bvh, rays, HitBatch{&t, &prim, &kind, &u, &v}, mode, 1, &wide);
                ADD_FAILURE() << "intersect_batch accepted tmin " << tmin;
            } catch (const std::invalid_argument& e) {
                EXPECT_NE(std::string(e.what()).find("the rays: tmin must be a number >= 0, got"), std::string::npos)
                    << e.what();
            }
            EXPECT_THROW(occluded_batch(bvh, rays, &out, mode, 1, &wide), std::invalid_argument);
        }
    }
    intersect_batch(bvh, RayBatch{o, d, 1, -0.0f, kInfinity}, HitBatch{&t, &prim, &kind, &u, &v}, Traversal::Wide, 1,
                    &wide);  // -0 is 0
    EXPECT_EQ(t, kInfinity);
}

}  // namespace
