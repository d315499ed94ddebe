// The two-level batch queries (intersect_batch_two_level, occluded_batch_two_level) on a batch
// that is reordered (ray_batch.h for_each_block, the timed choice forced) and on one that is not:
// every result lands in its own ray's slot, equal bit for bit to the ray traced alone (t, u, v,
// primitive, instance, visited count, occluded), on every traversal and with 1 and 3 threads; a
// refused ray in the reordered part is named by its index in the caller's batch.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "bvhlab/render_settings.h"
#include "bvhlab/tlas.h"
#include "ray_order.h"
#include "traverse_oracles.h"
#include "two_level_fixture.h"

using namespace bvhlab;
using test::same_bits;
using Arrays = test::RayArrays;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// 300 instances of two meshes (a triangle soup and a sphere), rotated, scaled (some mirrored) and
/// spread over the test cube, where test::random_rays go.
struct ManyInstances : test::TwoLevelFixture {
    ManyInstances() {
        meshes.push_back(test::random_scene(200, 0, 5));
        meshes.push_back(test::octasphere(3, {0, 0, 0}, 4.0f));
        std::mt19937 rng(11);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        std::vector<std::uint32_t> blas_of;
        std::vector<Transform> transforms;
        for (std::uint32_t i = 0; i < 300; ++i) {
            const float s = 0.05f + 0.1f * u(rng);
            blas_of.push_back(i % 3 == 0 ? 1u : 0u);
            transforms.push_back(test::make_transform({u(rng), u(rng), 0.2f + u(rng)}, 6.28f * u(rng),
                                                      {i % 7 == 0 ? -s : s, s, s},
                                                      {10 * u(rng), 10 * u(rng), 10 * u(rng)}));
        }
        build_two_level(blas_of, transforms);
    }
};

/// The timed choice made one way (detail::order_stall_ns: -inf reorders every timed block, +inf
/// none) while alive, the default after, also where an assertion returns early.
struct ForcedOrder {
    double before;
    explicit ForcedOrder(double stall) : before(detail::order_stall_ns.exchange(stall)) {}
    ~ForcedOrder() { detail::order_stall_ns = before; }
};

/// Random rays, a third with their own tmax, enough for a timed block (kOrderTimedLeast) and not in
/// ray order.
std::vector<Ray> batch_rays(const ManyInstances& s) {
    auto rays = test::random_rays(std::uint32_t(kOrderTimedLeast + 3000), 29);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.5f, 12.0f);
    for (std::size_t i = 0; i < rays.size(); i += 3) rays[i].tmax = u(rng);
    const Arrays arrays(rays);
    EXPECT_FALSE(in_ray_order(arrays.batch(), RayKeys(node_box(s.tlas.tree.nodes[0]), rays.size())));
    return rays;
}

}  // namespace

TEST(TlasBatchOrder, EachRayGetsItsOwnHitReorderedOrNot) {
    const ManyInstances s;
    const auto rays = batch_rays(s);
    const Arrays arrays(rays);
    const std::size_t n = rays.size();
    for (const double stall : {-kInf, kInf}) {
        const ForcedOrder forced(stall);
        for (Traversal mode : {Traversal::Wide, Traversal::Stack, Traversal::Stackless}) {
            for (std::uint32_t threads : {1u, 3u}) {
                SCOPED_TRACE(std::string(stall < 0 ? "reordered, " : "in order, ") + to_string(mode) + ", " +
                             std::to_string(threads) + " threads");
                std::vector<float> t(n), u(n), v(n);
                std::vector<std::int32_t> prim(n), instance(n);
                std::vector<std::uint8_t> kind(n);
                std::vector<std::uint32_t> visited(n);
                const std::unique_ptr<bool[]> blocked(new bool[n]);
                intersect_batch_two_level(s.two_level, arrays.batch(),
                                          {t.data(), prim.data(), kind.data(), u.data(), v.data(), visited.data()},
                                          instance.data(), mode, threads);
                occluded_batch_two_level(s.two_level, arrays.batch(), blocked.get(), mode, threads);
                std::size_t wrong = 0, hits = 0;
                for (std::size_t i = 0; i < n; ++i) {
                    std::uint32_t one_visited = 0;
                    const InstanceHit one = intersect_two_level(s.two_level, rays[i], mode, &one_visited);
                    const bool miss = one.hit.ref == kNoHit;
                    const bool ok = same_bits(t[i], one.hit.t) &&
                                    (miss || (same_bits(u[i], one.hit.u) && same_bits(v[i], one.hit.v))) &&
                                    prim[i] == (miss ? -1 : std::int32_t(one.hit.ref)) && kind[i] == 0 &&
                                    instance[i] == (miss ? -1 : std::int32_t(one.instance)) &&
                                    visited[i] == one_visited && blocked[i] == !miss &&
                                    blocked[i] == occluded_two_level(s.two_level, rays[i], mode);
                    if (!ok && ++wrong <= 5) ADD_FAILURE() << "ray " << i;
                    hits += !miss;
                }
                EXPECT_EQ(wrong, 0u);
                // both outcomes common: a batch of all misses or all hits would test little
                EXPECT_GT(hits, n / 20);
                EXPECT_LT(hits, n - n / 20);
            }
        }
    }
}

TEST(TlasBatchOrder, ARefusedRayInTheReorderedPartIsNamedByItsIndexInTheBatch) {
    const ManyInstances s;
    const auto rays = batch_rays(s);
    const ForcedOrder forced(-kInf);
    for (const std::size_t bad : {std::size_t(5), kOrderWarmRays + 7, rays.size() - 2}) {
        Arrays arrays(rays);
        arrays.d[3 * bad + 1] = std::numeric_limits<float>::quiet_NaN();
        const std::string name = "ray " + std::to_string(bad);
        std::vector<float> t(rays.size());
        std::vector<std::int32_t> prim(rays.size());
        const std::unique_ptr<bool[]> blocked(new bool[rays.size()]);
        for (std::uint32_t threads : {1u, 2u}) {
            try {
                intersect_batch_two_level(s.two_level, arrays.batch(), {t.data(), prim.data()}, nullptr,
                                          Traversal::Wide, threads);
                ADD_FAILURE() << "intersect_batch_two_level accepted a NaN direction";
            } catch (const std::invalid_argument& e) {
                EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
            }
            try {
                occluded_batch_two_level(s.two_level, arrays.batch(), blocked.get(), Traversal::Wide, threads);
                ADD_FAILURE() << "occluded_batch_two_level accepted a NaN direction";
            } catch (const std::invalid_argument& e) {
                EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
            }
        }
    }
}

TEST(TlasBatchOrder, AnEmptyBatchIsAnsweredWithNothing) {
    const ManyInstances s;
    const RayBatch none{nullptr, nullptr, 0};
    for (std::uint32_t threads : {1u, 3u}) {
        EXPECT_NO_THROW(intersect_batch_two_level(s.two_level, none, {}, nullptr, Traversal::Wide, threads));
        EXPECT_NO_THROW(occluded_batch_two_level(s.two_level, none, nullptr, Traversal::Wide, threads));
    }
}
