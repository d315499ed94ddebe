// The wide tree's batch queries (intersect_wide_batch, occluded_wide_batch, and intersect_batch /
// occluded_batch, which trace their chunks through them grouped by ray octant): every result lands
// in its own ray's slot, equal bit for bit to the ray traced alone and to the brute force, whatever
// the order of the rays, the instruction set path and the number of threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/isa.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"
#include "test_scenes.h"
#include "traverse_oracles.h"

using namespace bvhlab;
using test::brute_force;
using test::random_rays;
using test::same_bits;
using test::same_hit;
using test::supported_isas;

namespace {

/// Rays of all eight octants in shuffled order, several batch pieces (kWideBatch) and part of one, with
/// directions whose components are +0 or -0 (octant by the sign bit: -0 is a negative octant, as
/// 1/-0 = -inf), and each ray's own tmax from a few cases (a miss's t is tmax until finished).
std::vector<Ray> shuffled_rays(std::uint32_t seed) {
    auto rays = random_rays(8 * kWideBatch + 300, seed);
    for (std::size_t i = 0; i < rays.size(); i += 13)
        if (rays[i].dir.y != 0.0f || rays[i].dir.z != 0.0f) rays[i].dir.x = (i / 13) % 2 ? 0.0f : -0.0f;
    for (std::size_t i = 0; i < rays.size(); i += 17)
        if (rays[i].dir.x != 0.0f || rays[i].dir.y != 0.0f) rays[i].dir.z = (i / 17) % 2 ? 0.0f : -0.0f;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.5f, 20.0f);
    for (std::size_t i = 0; i < rays.size(); i += 4) rays[i].tmax = u(rng);
    std::shuffle(rays.begin(), rays.end(), rng);
    return rays;
}

}  // namespace

TEST(WideBatch, ShuffledMixedOctantsGiveEachRayItsOwnHitOnEveryPath) {
    const auto scene = test::random_scene(3000, 200, 41);
    const Bvh bvh = build_bvh(scene.view());
    const WideBvh wide = make_wide(bvh);
    const auto rays = shuffled_rays(43);
    int octants = 0;
    for (int k = 0; k < 8; ++k)
        octants += std::any_of(rays.begin(), rays.end(), [k](const Ray& r) {
            return (int(std::signbit(r.dir.x)) | int(std::signbit(r.dir.y)) << 1 | int(std::signbit(r.dir.z)) << 2) ==
                   k;
        });
    ASSERT_EQ(octants, 8);
    const Isa before = active_isa();
    // counted on the first path only: the plain C++ build has one, others two (same results)
    std::uint32_t hits = 0, blocked = 0, beyond = 0;
    bool first = true;
    for (Isa isa : supported_isas())
        for (WideWalk walk : {WideWalk::Alone, WideWalk::Interleaved}) {
            set_isa(isa);
            std::vector<Hit> batch(rays.size());
            std::vector<std::uint32_t> visited(rays.size());
            intersect_wide_batch(wide, bvh, rays.data(), rays.size(), batch.data(), visited.data(), walk);
            std::vector<char> occluded(rays.size());
            occluded_wide_batch(wide, rays.data(), rays.size(), reinterpret_cast<bool*>(occluded.data()));
            // without visited counts, camera-like runs of rays go as packets and the rest alone
            std::vector<Hit> uncounted(rays.size());
            intersect_wide_batch(wide, bvh, rays.data(), rays.size(), uncounted.data(), nullptr, walk);
            std::uint32_t wrong = 0;
            for (std::size_t i = 0; i < rays.size(); ++i) {
                std::uint32_t one_visited = 0;
                const Hit one = intersect_wide(wide, bvh, rays[i], &one_visited), oracle = brute_force(bvh, rays[i]);
                const bool ok = same_hit(batch[i], one) && same_hit(uncounted[i], one) && visited[i] == one_visited &&
                                batch[i].ref == oracle.ref && same_bits(batch[i].t, oracle.t) &&
                                bool(occluded[i]) == occluded_wide(wide, rays[i]) &&
                                bool(occluded[i]) == (oracle.t < rays[i].tmax);
                if (!ok && ++wrong <= 5)
                    ADD_FAILURE() << isa_name(isa) << (walk == WideWalk::Interleaved ? ", interleaved" : "") << ": ray "
                                  << i;
                if (!first) continue;
                hits += batch[i].ref != kNoHit, blocked += bool(occluded[i]);
                Ray unbounded = rays[i];
                unbounded.tmax = kInfinity;
                beyond += !occluded[i] && brute_force(bvh, unbounded).ref != kNoHit;
            }
            first = false;
        }
    set_isa(before);
    EXPECT_GT(hits, rays.size() / 5) << "too few hits to test anything";  // 533 of 2,348 here
    EXPECT_GT(blocked, rays.size() / 5);
    EXPECT_GE(beyond, 10u) << "some rays should hit only beyond their tmax";  // 20 here
}

/// The interleaved walk (wide_bvh.h WideWalk::Interleaved) on batches of fewer rays than it keeps
/// walkers, as many, and a few more, of one octant, where each walker's ray ends at its own time
/// (misses after a node or two, hits deep in the tree, rays cut short by their tmax) and hands its
/// place on: every ray's hit and visited count its single walk's.
TEST(WideBatch, InterleavedWalksOfAnyCountGiveEachRayItsOwnHit) {
    const auto scene = test::random_scene(4000, 100, 91);
    const Bvh bvh = build_bvh(scene.view());
    const WideBvh wide = make_wide(bvh);
    std::vector<Ray> all;
    for (const Ray& r : random_rays(4000, 93))
        if (!std::signbit(r.dir.x) && !std::signbit(r.dir.y) && std::signbit(r.dir.z)) all.push_back(r);
    ASSERT_GE(all.size(), 40u);
    for (std::size_t i = 0; i < all.size(); i += 5) all[i].tmax = 0.5f + float(i % 7);
    const Isa before = active_isa();
    std::uint32_t hits = 0;
    for (Isa isa : supported_isas()) {
        set_isa(isa);
        for (std::size_t n : {0, 1, 2, 7, 8, 9, 15, 16, 17, 40}) {
            std::vector<Hit> got(n);
            std::vector<std::uint32_t> visited(n);
            intersect_wide_batch(wide, bvh, all.data(), n, got.data(), visited.data(), WideWalk::Interleaved);
            for (std::size_t i = 0; i < n; ++i) {
                std::uint32_t one_visited = 0;
                const Hit one = intersect_wide(wide, bvh, all[i], &one_visited);
                EXPECT_TRUE(same_hit(got[i], one)) << isa_name(isa) << ", " << n << " rays: ray " << i;
                EXPECT_EQ(visited[i], one_visited) << isa_name(isa) << ", " << n << " rays: ray " << i;
                if (n == 40) hits += one.ref != kNoHit;
            }
        }
    }
    set_isa(before);
    EXPECT_GT(hits, 5u) << "too few hits to test anything";
}

TEST(WideBatch, BatchQueriesMatchTheStackTraversalOnAnyThreadCount) {
    const auto scene = test::random_scene(2500, 150, 47);
    const Bvh bvh = build_bvh(scene.view());
    const WideBvh wide = make_wide(bvh);
    const auto rays = shuffled_rays(53);
    std::vector<float> o, d, tmax;
    for (const Ray& r : rays) {
        o.insert(o.end(), {r.origin.x, r.origin.y, r.origin.z}), d.insert(d.end(), {r.dir.x, r.dir.y, r.dir.z});
        tmax.push_back(r.tmax);
    }
    RayBatch batch;
    batch.origins = o.data(), batch.directions = d.data(), batch.count = rays.size(), batch.tmax_of = tmax.data();
    struct Out {
        std::vector<float> t, u, v;
        std::vector<std::int32_t> prim;
        std::vector<std::uint8_t> kind;
        std::vector<char> occluded;
    };
    auto run = [&](Traversal mode, std::uint32_t threads) {
        const std::size_t n = rays.size();
        Out out{std::vector<float>(n),        std::vector<float>(n),        std::vector<float>(n),
                std::vector<std::int32_t>(n), std::vector<std::uint8_t>(n), std::vector<char>(n)};
        HitBatch hits;
        hits.t = out.t.data(), hits.prim = out.prim.data(), hits.kind = out.kind.data(), hits.u = out.u.data();
        hits.v = out.v.data();
        intersect_batch(bvh, batch, hits, mode, threads, &wide);
        occluded_batch(bvh, batch, reinterpret_cast<bool*>(out.occluded.data()), mode, threads, &wide);
        return out;
    };
    const Out stack = run(Traversal::Stack, 1);
    const Isa before = active_isa();
    for (Isa isa : supported_isas()) {
        set_isa(isa);
        for (std::uint32_t threads : {1u, 2u, 4u}) {
            const Out got = run(Traversal::Wide, threads);
            std::uint32_t wrong = 0;
            for (std::size_t i = 0; i < rays.size(); ++i) {
                const bool ok = same_bits(got.t[i], stack.t[i]) && got.prim[i] == stack.prim[i] &&
                                got.kind[i] == stack.kind[i] && same_bits(got.u[i], stack.u[i]) &&
                                same_bits(got.v[i], stack.v[i]) && got.occluded[i] == stack.occluded[i] &&
                                bool(got.occluded[i]) == (got.t[i] < tmax[i]);
                if (!ok && ++wrong <= 5)
                    ADD_FAILURE() << isa_name(isa) << ", " << threads << " threads: ray " << i << " t " << got.t[i]
                                  << " against " << stack.t[i];
            }
        }
    }
    set_isa(before);
}

/// The batch's any-hit walk takes its order per piece from the piece's first rays (wide_batch.inl
/// occluded_of_batch: those of the lowest octant present, as the piece is grouped): every second
/// piece here has its octant-0 rays cut short, so that they reach nothing and the rest of the piece,
/// many of them occluded, goes in the layout's order; the other pieces mostly farthest first. Both
/// give the brute force's answer and the single ray's on every ray and path.
TEST(WideBatch, AnyHitOrderChosenPerPieceGivesTheBruteForcesAnswers) {
    const auto scene = test::random_scene(3000, 200, 61);
    const Bvh bvh = build_bvh(scene.view());
    const WideBvh wide = make_wide(bvh);
    auto rays = random_rays(6 * kWideBatch, 67);
    auto layout_piece = [](std::size_t i) { return (i / kWideBatch) % 2 == 0; };
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const Vec3 d = rays[i].dir;
        if (layout_piece(i) && !std::signbit(d.x) && !std::signbit(d.y) && !std::signbit(d.z)) rays[i].tmax = 1e-6f;
    }
    std::vector<char> oracle(rays.size());
    std::uint32_t occluded_in_layout = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        oracle[i] = brute_force(bvh, rays[i]).t < rays[i].tmax;
        occluded_in_layout += layout_piece(i) && oracle[i];
    }
    EXPECT_GT(occluded_in_layout, 100u) << "too few occluded rays in the layout's order to test it";
    const Isa before = active_isa();
    for (Isa isa : supported_isas()) {
        set_isa(isa);
        std::vector<char> occluded(rays.size());
        occluded_wide_batch(wide, rays.data(), rays.size(), reinterpret_cast<bool*>(occluded.data()));
        std::uint32_t wrong = 0;
        for (std::size_t i = 0; i < rays.size(); ++i)
            if ((occluded[i] != oracle[i] || bool(occluded[i]) != occluded_wide(wide, rays[i])) && ++wrong <= 5)
                ADD_FAILURE() << isa_name(isa) << ": ray " << i << " occluded " << int(occluded[i]) << ", brute force "
                              << int(oracle[i]);
    }
    set_isa(before);
}

TEST(WideBatch, EmptyTreeAndEmptyBatch) {
    test::Scene empty;
    const Bvh none = build_bvh(empty.view());
    const WideBvh wide = make_wide(none);
    const auto rays = random_rays(10, 3);
    std::vector<Hit> hits(rays.size());
    std::vector<std::uint32_t> visited(rays.size(), 7);
    intersect_wide_batch(wide, none, rays.data(), rays.size(), hits.data(), visited.data());
    bool occluded[10];
    std::fill(occluded, occluded + 10, true);
    occluded_wide_batch(wide, rays.data(), rays.size(), occluded);
    for (std::size_t i = 0; i < rays.size(); ++i) {
        EXPECT_EQ(hits[i].ref, kNoHit);
        EXPECT_EQ(hits[i].t, kInfinity);
        EXPECT_EQ(visited[i], 0u);
        EXPECT_FALSE(occluded[i]);
    }
    intersect_wide_batch(wide, none, rays.data(), 0, hits.data());  // nothing to do, nothing read
    occluded_wide_batch(wide, rays.data(), 0, occluded);
}

/// The wide batch checks its rays as it reads them (ray_batch.h prepare_piece, on the bits of
/// |x|) rather than by check_rays before: it must refuse exactly what check_rays refuses, and
/// name the same (first) ray, wherever in the batch the ray is and on any thread count.
TEST(WideBatch, RefusesExactlyWhatCheckRaysRefuses) {
    const auto scene = test::random_scene(500, 40, 59);
    const Bvh bvh = build_bvh(scene.view());
    const WideBvh wide = make_wide(bvh);
    const float big = 0x1p40f, least = 0x1p-80f, most = 0x1p80f, nan = std::nanf(""), inf = kInfinity;
    struct Case {
        Vec3 origin, dir;
        float tmax;
    };
    const Case accepted[] = {
        {{big, -big, 0.0f}, {0.0f, 0.0f, 1.0f}, 5.0f},       {{0.0f, 0.0f, 0.0f}, {least, 0.0f, -0.0f}, 5.0f},
        {{0.0f, 0.0f, 0.0f}, {-0.0f, most, 1.0f}, 5.0f},     {{-0.0f, 0.0f, 0.0f}, {0.0f, -least, least}, 0.0f},
        {{1.0f, 2.0f, 3.0f}, {0x1p-149f, 0.0f, least}, inf},
    };
    const Case refused[] = {
        {{std::nextafter(big, inf), 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, 5.0f},
        {{0.0f, -std::nextafter(big, inf), 0.0f}, {0.0f, 0.0f, 1.0f}, 5.0f},
        {{0.0f, 0.0f, nan}, {0.0f, 0.0f, 1.0f}, 5.0f},
        {{0.0f, 0.0f, -inf}, {0.0f, 0.0f, 1.0f}, 5.0f},
        {{0.0f, 0.0f, 0.0f}, {std::nextafter(least, 0.0f), 0.0f, 0.0f}, 5.0f},
        {{0.0f, 0.0f, 0.0f}, {0.0f, -std::nextafter(most, inf), 0.0f}, 5.0f},
        {{0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, 5.0f},
        {{0.0f, 0.0f, 0.0f}, {1.0f, nan, 0.0f}, 5.0f},
        {{0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, -inf}, 5.0f},
        {{0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, nan},
        {{0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, -1.0f},
    };
    const auto rays = random_rays(3000, 61);
    auto batch_of = [&](const Case& c, std::size_t at, std::vector<float>& o, std::vector<float>& d,
                        std::vector<float>& tmax) {
        o.clear(), d.clear(), tmax.clear();
        for (std::size_t i = 0; i < rays.size(); ++i) {
            const Ray& r = rays[i];
            const Vec3 ro = i == at ? c.origin : r.origin, rd = i == at ? c.dir : r.dir;
            o.insert(o.end(), {ro.x, ro.y, ro.z}), d.insert(d.end(), {rd.x, rd.y, rd.z});
            tmax.push_back(i == at ? c.tmax : 10.0f);
        }
        RayBatch b;
        b.origins = o.data(), b.directions = d.data(), b.count = rays.size(), b.tmax_of = tmax.data();
        return b;
    };
    std::vector<float> o, d, tmax, t(rays.size()), t_stack(rays.size());
    std::vector<std::int32_t> prim(rays.size()), prim_stack(rays.size());
    std::vector<char> occluded(rays.size());
    const Isa before = active_isa();
    for (Isa isa : supported_isas()) {
        set_isa(isa);
        for (std::uint32_t threads : {1u, 3u}) {
            for (const Case& c : accepted) {
                const RayBatch b = batch_of(c, 2100, o, d, tmax);
                HitBatch hits, stack;
                hits.t = t.data(), hits.prim = prim.data(), stack.t = t_stack.data(), stack.prim = prim_stack.data();
                ASSERT_NO_THROW(intersect_batch(bvh, b, hits, Traversal::Wide, threads, &wide));
                ASSERT_NO_THROW(
                    occluded_batch(bvh, b, reinterpret_cast<bool*>(occluded.data()), Traversal::Wide, threads, &wide));
                intersect_batch(bvh, b, stack, Traversal::Stack, 1);
                EXPECT_TRUE(same_bits(t[2100], t_stack[2100]) && prim[2100] == prim_stack[2100]);
                EXPECT_EQ(bool(occluded[2100]), t_stack[2100] < c.tmax);
            }
            for (const Case& c : refused)
                for (std::size_t at : {std::size_t(5), std::size_t(2100), std::size_t(2101)}) {
                    const RayBatch b = batch_of(c, at, o, d, tmax);
                    if (at == 2101) o[3 * 2900 + 1] = nan;  // a second refused ray after it: the first is named
                    std::string expected;
                    try {
                        check_rays(b);
                    } catch (const std::invalid_argument& e) { expected = e.what(); }
                    ASSERT_NE(expected.find("ray " + std::to_string(at)), std::string::npos) << expected;
                    HitBatch hits;
                    hits.t = t.data(), hits.prim = prim.data();
                    try {
                        intersect_batch(bvh, b, hits, Traversal::Wide, threads, &wide);
                        ADD_FAILURE() << "accepted: " << expected;
                    } catch (const std::invalid_argument& e) { EXPECT_EQ(std::string(e.what()), expected); }
                    try {
                        occluded_batch(bvh, b, reinterpret_cast<bool*>(occluded.data()), Traversal::Wide, threads,
                                       &wide);
                        ADD_FAILURE() << "accepted: " << expected;
                    } catch (const std::invalid_argument& e) { EXPECT_EQ(std::string(e.what()), expected); }
                }
        }
    }
    set_isa(before);
}
