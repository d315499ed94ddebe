// The wide tree's batch queries (intersect_wide_batch, occluded_wide_batch, and intersect_batch /
// occluded_batch, which trace their chunks through them grouped by ray octant): every result lands
// in its own ray's slot, equal bit for bit to the ray traced alone and to the brute force, whatever
// the order of the rays, the instruction set path and the number of threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
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
using test::supported_isas;

namespace {

/// Rays of all eight octants in shuffled order, more than one batch piece (kWideBatch), with
/// directions whose components are +0 or -0 (octant by the sign bit: -0 is a negative octant, as
/// 1/-0 = -inf), and each ray's own tmax from a few cases (a miss's t is tmax until finished).
std::vector<Ray> shuffled_rays(std::uint32_t seed) {
    auto rays = random_rays(2 * kWideBatch + 300, seed);
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

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

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
    for (Isa isa : supported_isas()) {
        set_isa(isa);
        std::vector<Hit> batch(rays.size());
        std::vector<std::uint32_t> visited(rays.size());
        intersect_wide_batch(wide, bvh, rays.data(), rays.size(), batch.data(), visited.data());
        std::vector<char> occluded(rays.size());
        occluded_wide_batch(wide, rays.data(), rays.size(), reinterpret_cast<bool*>(occluded.data()));
        std::uint32_t wrong = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) {
            std::uint32_t one_visited = 0;
            const Hit one = intersect_wide(wide, bvh, rays[i], &one_visited), oracle = brute_force(bvh, rays[i]);
            const bool ok = same_bits(batch[i].t, one.t) && batch[i].ref == one.ref && same_bits(batch[i].u, one.u) &&
                            same_bits(batch[i].v, one.v) && batch[i].slot == one.slot && visited[i] == one_visited &&
                            batch[i].ref == oracle.ref && same_bits(batch[i].t, oracle.t) &&
                            bool(occluded[i]) == occluded_wide(wide, rays[i]) &&
                            bool(occluded[i]) == (oracle.t < rays[i].tmax);
            if (!ok && ++wrong <= 5) ADD_FAILURE() << isa_name(isa) << ": ray " << i;
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
