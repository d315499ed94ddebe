// Packets of coherent rays in the wide batch (wide_packet.inl: the AVX2 path's closest-hit batch
// walk takes eight rays of one octant with one origin and nearly one direction through the tree
// together): camera rays, cameras whose packets diverge, mixed octants in one piece, misses, tmin
// and tmax limits, spheres; and shadow rays of neighbouring points toward one light through the
// any-hit batch (where shadow packets were tried: design.md). Every hit must equal, bit for bit,
// the ray traced alone (intersect_wide) and the brute force, every answer the single any-hit
// walk's and the closest hit's, on every instruction set path and thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/isa.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"
#include "test_scenes.h"
#include "traverse_oracles.h"

using namespace bvhlab;
using test::brute_force;
using test::same_bits;
using test::same_hit;
using test::supported_isas;

namespace {

/// A pinhole camera's rays, row by row as the bench's primary rays (bench/_peers.py): from `eye`
/// towards `at`, `width` × `height` pixels over a vertical field of `fov` radians; `jitter`
/// radians of random turn per ray (0: a plain camera). A packet's rays are at most ~5.7° apart
/// (wide_packet.inl kPacketCos2): eight pixels of these cameras span 2.5-4°, and 1° at the bench's
/// 640 × 480.
std::vector<Ray> camera_rays(Vec3 eye, Vec3 at, int width, int height, float fov, float jitter = 0.0f,
                             std::uint32_t seed = 1) {
    const Vec3 f = normalize(at - eye), r = normalize(cross(f, Vec3{0.0f, 0.0f, 1.0f})), u = cross(r, f);
    const float step = 2.0f * std::tan(fov / 2) / float(height);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> turn(-jitter, jitter);
    std::vector<Ray> rays;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const float sx = (float(x) + 0.5f - 0.5f * float(width)) * step + turn(rng);
            const float sy = (0.5f * float(height) - float(y) - 0.5f) * step + turn(rng);
            Ray ray;
            ray.origin = eye, ray.dir = f + r * sx + u * sy;
            rays.push_back(ray);
        }
    return rays;
}

/// Compares intersect_wide_batch (no visited counts: the packet walk where the path has one, the
/// rays it does not take one after another and interleaved) with each ray alone and with the brute
/// force on every instruction set path; returns the hits.
std::size_t expect_batch_is_single(const Bvh& bvh, const std::vector<Ray>& rays) {
    const WideBvh wide = make_wide(bvh);
    const Isa before = active_isa();
    std::size_t hits = 0;
    for (Isa isa : supported_isas())
        for (WideWalk walk : {WideWalk::Alone, WideWalk::Interleaved}) {
            set_isa(isa);
            std::vector<Hit> batch(rays.size());
            intersect_wide_batch(wide, bvh, rays.data(), rays.size(), batch.data(), nullptr, walk);
            std::uint32_t wrong = 0;
            hits = 0;
            for (std::size_t i = 0; i < rays.size(); ++i) {
                const Hit one = intersect_wide(wide, bvh, rays[i]), oracle = brute_force(bvh, rays[i]);
                const bool ok =
                    same_hit(batch[i], one) && batch[i].ref == oracle.ref && same_bits(batch[i].t, oracle.t);
                if (!ok && ++wrong <= 5)
                    ADD_FAILURE() << isa_name(isa) << (walk == WideWalk::Interleaved ? ", interleaved" : "") << ": ray "
                                  << i << " t " << batch[i].t << " ref " << batch[i].ref << " against " << one.t
                                  << " ref " << one.ref << " (brute force " << oracle.t << ")";
                hits += one.ref != kNoHit;
            }
        }
    set_isa(before);
    return hits;
}

/// Compares occluded_wide_batch with each ray alone and with the closest hit (t < tmax) on every
/// instruction set path; returns how many are occluded.
std::size_t expect_occluded_batch_is_single(const Bvh& bvh, const std::vector<Ray>& rays) {
    const WideBvh wide = make_wide(bvh);
    const Isa before = active_isa();
    std::size_t occluded = 0;
    for (Isa isa : supported_isas()) {
        set_isa(isa);
        std::unique_ptr<bool[]> batch(new bool[rays.size()]);
        occluded_wide_batch(wide, rays.data(), rays.size(), batch.get());
        std::uint32_t wrong = 0;
        occluded = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) {
            const bool one = occluded_wide(wide, rays[i]),
                       oracle = intersect(bvh, rays[i], Traversal::Stack).t < rays[i].tmax;
            if ((batch[i] != one || one != oracle) && ++wrong <= 5)
                ADD_FAILURE() << isa_name(isa) << ": shadow ray " << i << " batch " << batch[i] << " alone " << one
                              << " closest hit " << oracle;
            occluded += one;
        }
    }
    set_isa(before);
    return occluded;
}

/// Shadow rays toward a light above the scene from the points a camera looking down on it hits,
/// in pixel order (neighbouring rays: neighbouring points, directions within a packet's cone).
std::vector<Ray> shadow_rays(const Bvh& bvh, Vec3 light, std::uint32_t seed) {
    std::vector<Ray> out;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (const Ray& ray : camera_rays({-6.0f, -4.0f, 12.0f}, {5.0f, 5.0f, 2.0f}, 128, 96, 0.9f)) {
        const Hit hit = intersect(bvh, ray, Traversal::Stack);
        if (hit.ref == kNoHit) continue;
        Ray shadow;
        shadow.origin = ray.origin + ray.dir * hit.t;
        shadow.dir = light - shadow.origin;
        shadow.tmin = 1e-4f;
        shadow.tmax = u(rng) < 0.2f ? 0.5f : 1.0f;  // some end halfway to the light
        out.push_back(shadow);
    }
    return out;
}

}  // namespace

TEST(WidePackets, CameraRaysGiveTheSingleRayHits) {
    const auto scene = test::random_scene(4000, 150, 71);  // triangles and spheres
    const Bvh bvh = build_bvh(scene.view());
    const auto rays = camera_rays({-6.0f, -4.0f, 3.0f}, {5.0f, 5.0f, 5.0f}, 96, 64, 0.6f);
    EXPECT_GT(expect_batch_is_single(bvh, rays), rays.size() / 3);
}

/// Rays within the packet's cone of one another but turned at random: the packet's rays part
/// in the tree and each enters children the others do not.
TEST(WidePackets, PartlyCoherentRaysGiveTheSingleRayHits) {
    const auto scene = test::random_scene(4000, 150, 73);
    const Bvh bvh = build_bvh(scene.view());
    for (float jitter : {0.005f, 0.02f, 0.3f}) {  // the last refused as packets
        const auto rays = camera_rays({-6.0f, -4.0f, 3.0f}, {5.0f, 5.0f, 5.0f}, 128, 96, 0.6f, jitter, 5);
        EXPECT_GT(expect_batch_is_single(bvh, rays), rays.size() / 4) << jitter;
    }
}

/// A camera inside the scene looking along an axis: the view spans four octants (each piece of
/// 256 rays holds rays of several, grouped before the walk), and looking out of the scene's
/// cube, part of the rays miss everything.
TEST(WidePackets, MixedOctantsAndMissesGiveTheSingleRayHits) {
    const auto scene = test::random_scene(4000, 150, 79);
    const Bvh bvh = build_bvh(scene.view());
    const auto rays = camera_rays({5.0f, 5.0f, 5.0f}, {5.0f, 15.0f, 5.0f}, 192, 144, 1.2f);
    int octants = 0;
    for (int k = 0; k < 8; ++k)
        for (const Ray& r : rays)
            if ((int(std::signbit(r.dir.x)) | int(std::signbit(r.dir.y)) << 1 | int(std::signbit(r.dir.z)) << 2) == k) {
                ++octants;
                break;
            }
    EXPECT_GE(octants, 4);
    const std::size_t hits = expect_batch_is_single(bvh, rays);
    EXPECT_GT(hits, rays.size() / 10);
    EXPECT_LT(hits, rays.size() * 9 / 10) << "some rays should miss";
    // a camera outside looking away: every ray misses
    const auto away = camera_rays({-6.0f, -4.0f, 3.0f}, {-16.0f, -14.0f, 3.0f}, 64, 48, 0.5f);
    EXPECT_EQ(expect_batch_is_single(bvh, away), 0u);
}

/// Each ray's own tmin and tmax (a packet's rays end at different distances): a ray whose hit
/// lies beyond its tmax, or before its tmin, must not take it from a packet neighbour's walk.
TEST(WidePackets, TminAndTmaxLimitsGiveTheSingleRayHits) {
    const auto scene = test::random_scene(4000, 150, 83);
    const Bvh bvh = build_bvh(scene.view());
    auto rays = camera_rays({-6.0f, -4.0f, 3.0f}, {5.0f, 5.0f, 5.0f}, 128, 96, 0.9f);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (Ray& r : rays) {
        if (u(rng) < 0.5f) r.tmax = 2.0f + 14.0f * u(rng);
        if (u(rng) < 0.25f) r.tmin = 6.0f * u(rng);
    }
    EXPECT_GT(expect_batch_is_single(bvh, rays), rays.size() / 5);
}

/// A packet whose rays run in a plane of the tree's boxes: tents standing on z = 5 (each a
/// vertical triangle, its base on the plane, so every box ends at z = 5), seen from z = 5 inside
/// the field by rays taken down each column, the middle row's direction z −0. A packet holds that
/// ray and seven going down, which enter the boxes around the eye at t = 0 and none ahead; its
/// bound of −(1/d_z)·s is +inf, and 0 · inf (the eye's distance to the boxes' far plane z = 5) is
/// NaN, which each ray's own test ignores (the middle ray grazes the tents' base edges ahead and
/// hits them). The packet's whole-node cull (wide_packet.inl maybe_entered) must not drop the
/// boxes ahead: without its check of the factors (Interval::valid), it does (t 0.566 where 0.203).
TEST(WidePackets, RaysInABoxPlaneWithZeroDirectionComponentsGiveTheSingleRayHits) {
    test::Scene scene;
    std::mt19937 rng(97);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int i = 0; i < 3000; ++i) {
        const float x = 10.0f * u(rng), y = 1.0f + 9.0f * u(rng), w = 0.2f + 0.8f * u(rng), h = 0.2f + u(rng);
        scene.add_triangle({x, y, 5.0f}, {x + w, y, 5.0f}, {x + 0.5f * w, y, 5.0f + h});
    }
    const Bvh bvh = build_bvh(scene.view());
    const int width = 64, height = 33;        // odd: the middle row's z is 0
    const float step = 0.2f / float(height);  // eight rays of a column within a packet's cone
    std::vector<Ray> rays;
    std::size_t middle = 0;
    for (int x = 0; x < width; ++x)
        for (int y = 0; y < height; ++y) {
            Ray ray;
            ray.origin = {5.0f, 5.0f, 5.0f};  // inside the boxes: rays going down enter them at t = 0
            const float sz = (0.5f * float(height) - float(y) - 0.5f) * step;
            ray.dir = {(float(x) + 0.5f - 0.5f * float(width)) * step, 1.0f, sz == 0.0f ? -0.0f : sz};
            middle += sz == 0.0f;
            rays.push_back(ray);
        }
    ASSERT_EQ(middle, std::size_t(width));
    std::size_t edge_hits = 0;
    for (const Ray& ray : rays) edge_hits += ray.dir.z == 0.0f && intersect(bvh, ray, Traversal::Stack).ref != kNoHit;
    EXPECT_GT(edge_hits, std::size_t(width) / 2) << "the middle row's rays should hit the tents' base edges";
    EXPECT_GT(expect_batch_is_single(bvh, rays), rays.size() / 4);
}

/// Bvh.intersect's entry point (intersect_batch: checked, scaled pieces) with camera rays on 1
/// and 3 threads: the same hits as the binary stack walk, every path.
TEST(WidePackets, IntersectBatchOnThreadsGivesTheStackWalksHits) {
    const auto scene = test::random_scene(4000, 150, 89);
    const Bvh bvh = build_bvh(scene.view());
    const WideBvh wide = make_wide(bvh);
    const auto rays = camera_rays({-6.0f, -4.0f, 3.0f}, {5.0f, 5.0f, 5.0f}, 160, 120, 0.5f);
    std::vector<float> o, d;
    for (const Ray& r : rays)
        o.insert(o.end(), {r.origin.x, r.origin.y, r.origin.z}), d.insert(d.end(), {r.dir.x, r.dir.y, r.dir.z});
    RayBatch batch;
    batch.origins = o.data(), batch.directions = d.data(), batch.count = rays.size(), batch.tmax = 30.0f;
    auto run = [&](Traversal mode, std::uint32_t threads, std::vector<float>& t, std::vector<std::int32_t>& prim,
                   std::vector<float>& u, std::vector<float>& v) {
        t.resize(rays.size()), prim.resize(rays.size()), u.resize(rays.size()), v.resize(rays.size());
        HitBatch hits;
        hits.t = t.data(), hits.prim = prim.data(), hits.u = u.data(), hits.v = v.data();
        intersect_batch(bvh, batch, hits, mode, threads, &wide);
    };
    std::vector<float> t0, u0, v0, t, u, v;
    std::vector<std::int32_t> prim0, prim;
    run(Traversal::Stack, 1, t0, prim0, u0, v0);
    const Isa before = active_isa();
    for (Isa isa : supported_isas()) {
        set_isa(isa);
        for (std::uint32_t threads : {1u, 3u}) {
            run(Traversal::Wide, threads, t, prim, u, v);
            std::uint32_t wrong = 0;
            for (std::size_t i = 0; i < rays.size(); ++i) {
                const bool ok =
                    same_bits(t[i], t0[i]) && prim[i] == prim0[i] && same_bits(u[i], u0[i]) && same_bits(v[i], v0[i]);
                if (!ok && ++wrong <= 5)
                    ADD_FAILURE() << isa_name(isa) << ", " << threads << " threads: ray " << i << " t " << t[i]
                                  << " against " << t0[i];
            }
        }
    }
    set_isa(before);
}

/// Shadow rays from the points a camera sees toward one light, in pixel order (the rays a packet
/// of shadow rays would take; design.md "Shadow packets, tried"): in a sparse scene most reach the
/// light (the batch's pieces go in the layout's order), in a dense one most are occluded
/// (farthest first); every answer the single walk's and the closest hit's, every path.
TEST(WidePackets, ShadowRaysGiveTheSingleRayAnswers) {
    for (std::uint32_t triangles : {300u, 4000u}) {
        auto scene = test::random_scene(triangles, triangles / 20, 101);
        scene.add_triangle({-30.0f, -30.0f, 0.0f}, {40.0f, -30.0f, 0.0f}, {40.0f, 40.0f, 0.0f});  // a floor
        scene.add_triangle({-30.0f, -30.0f, 0.0f}, {40.0f, 40.0f, 0.0f}, {-30.0f, 40.0f, 0.0f});
        const Bvh bvh = build_bvh(scene.view());
        const auto rays = shadow_rays(bvh, {5.0f, 4.0f, 30.0f}, 3);
        ASSERT_GT(rays.size(), 2000u);
        const std::size_t occluded = expect_occluded_batch_is_single(bvh, rays);
        if (triangles == 300u) {
            EXPECT_LT(occluded, rays.size() / 4) << "most should reach the light";
        } else {
            EXPECT_GT(occluded, rays.size() / 4);
        }
        EXPECT_GT(occluded, 0u);
    }
}
