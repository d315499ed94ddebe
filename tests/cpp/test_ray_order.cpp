// The order in which the wide tree's batch queries trace an incoherent batch (src/query/ray_order.h):
// the keys, the check of an order already good, the sort, the loop that probes a block and traces
// it in ray order (ray_batch.h for_each_block), and intersect_batch / occluded_batch on a
// batch that is reordered: every result lands in its own ray's slot, equal bit for bit to the ray
// traced alone, on every instruction set path and thread count; a refused ray is still named.
#include <gtest/gtest.h>
#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/isa.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"
#include "ray_batch.h"
#include "ray_order.h"
#include "test_scenes.h"
#include "traverse_oracles.h"

using namespace bvhlab;
using test::random_rays;
using test::same_bits;
using Arrays = test::RayArrays;
using test::supported_isas;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

std::uint32_t key(const RayKeys& keys, Vec3 o, Vec3 d) {
    const float origin[3] = {o.x, o.y, o.z}, direction[3] = {d.x, d.y, d.z};
    return keys(origin, direction);
}

}  // namespace

TEST(RayOrder, KeysAreTheOctantAboveTheMortonCodeOfTheOriginsCellForAnyOrigin) {
    const RayKeys keys({{0, 0, 0}, {16, 16, 16}}, 16 * kOrderLeast);  // 16 cells an axis, one unit each
    ASSERT_EQ(keys.bits, 4);
    ASSERT_EQ(keys.count(), 8u << 12);
    const Vec3 up{1, 1, 1};
    EXPECT_EQ(key(keys, {0.5f, 0.5f, 0.5f}, up), 0u);
    EXPECT_EQ(key(keys, {1.5f, 0.5f, 0.5f}, up), 1u);  // x in bit 0, y in bit 1, z in bit 2
    EXPECT_EQ(key(keys, {0.5f, 1.5f, 0.5f}, up), 2u);
    EXPECT_EQ(key(keys, {0.5f, 0.5f, 1.5f}, up), 4u);
    EXPECT_EQ(key(keys, {2.5f, 0.5f, 0.5f}, up), 8u);
    EXPECT_EQ(key(keys, {15.9f, 15.9f, 15.9f}, up), 0xfffu);
    EXPECT_EQ(key(keys, {0.5f, 0.5f, 0.5f}, {-1, 1, 1}), 1u << 12);  // octant: the sign bits of the direction
    EXPECT_EQ(key(keys, {0.5f, 0.5f, 0.5f}, {1, -0.0f, 1}), 2u << 12);
    EXPECT_EQ(key(keys, {1.5f, 0.5f, 0.5f}, {-1, -1, -1}), 7u << 12 | 1u);
    // outside the box, infinite or not a number: the nearest cell, or cell 0, never past the table
    EXPECT_EQ(key(keys, {-5, 100, 0.5f}, up), key(keys, {0, 15.5f, 0.5f}, up));
    for (float x : {kNaN, kInfinity, -kInfinity, 1e30f, -1e30f, 3e38f})
        EXPECT_LT(key(keys, {x, x, 0.5f}, {x, 1, 1}), keys.count()) << x;
    // a box flat on an axis, tiny or empty: that axis in cell 0
    for (const Aabb& box : {Aabb{{0, 0, 5}, {16, 16, 5}}, Aabb{{0, 0, 0}, {16, 16, 1e-44f}}})
        EXPECT_EQ(key(RayKeys(box, 16 * kOrderLeast), {1.5f, 0.5f, 7}, up), 1u);
    EXPECT_EQ(key(RayKeys(Aabb{}, kOrderLeast), {1.5f, 0.5f, 7}, up), 0u);
    EXPECT_EQ(RayKeys(Aabb{}, kOrderLeast).bits, 3);
}

TEST(RayOrder, CameraRaysKeepTheirOrderAndRandomOnesAreSortedStably) {
    const Aabb box{{-2, -2, -2}, {12, 12, 12}};
    // a camera's rays (one origin, neighbouring pixels): in order already
    std::vector<Ray> camera;
    for (int y = 0; y < 80; ++y)
        for (int x = 0; x < 100; ++x) camera.push_back({{5, 5, -1}, {float(x - 50), float(y - 40), 60}});
    const Arrays cam(camera);
    EXPECT_TRUE(in_ray_order(cam.batch(), RayKeys(box, camera.size())));
    const auto rays = random_rays(20000, 5);
    const Arrays arrays(rays);
    const RayBatch batch = arrays.batch();
    const RayKeys keys(box, batch.count);
    EXPECT_FALSE(in_ray_order(batch, keys));
    SortedRays sorted;
    sort_rays(batch, keys, sorted);
    const auto& index = sorted.index;
    ASSERT_EQ(index.size(), rays.size());
    ASSERT_EQ(sorted.tmax_of.size(), rays.size());
    std::vector<char> seen(rays.size(), 0);
    std::uint32_t runs = 0;
    for (std::size_t k = 0; k < index.size(); ++k) {
        ASSERT_LT(index[k], rays.size());
        ASSERT_FALSE(seen[index[k]]) << "ray " << index[k] << " twice";
        seen[index[k]] = 1;
        for (int a = 0; a < 3; ++a) {  // position k holds ray index[k]
            ASSERT_TRUE(same_bits(sorted.origins[3 * k + a], arrays.o[3 * index[k] + a])) << k;
            ASSERT_TRUE(same_bits(sorted.directions[3 * k + a], arrays.d[3 * index[k] + a])) << k;
        }
        ASSERT_TRUE(same_bits(sorted.tmax_of[k], arrays.tmax[index[k]])) << k;
        if (k == 0) continue;
        const std::uint32_t a = keys(&arrays.o[3 * index[k - 1]], &arrays.d[3 * index[k - 1]]),
                            b = keys(&arrays.o[3 * index[k]], &arrays.d[3 * index[k]]);
        ASSERT_LE(a, b) << k;
        if (a == b) ASSERT_LT(index[k - 1], index[k]) << k;  // ties in input order
        runs += a != b;
    }
    EXPECT_GT(runs, 1000u);  // the rays spread over many keys: the check above compared something
    // the copy is a batch in ray order; the results put back land in their own rays' slots
    const RayBatch copy = sorted.batch(batch);
    EXPECT_EQ(copy.count, batch.count);
    EXPECT_EQ(copy.tmax_of, sorted.tmax_of.data());
    EXPECT_TRUE(in_ray_order(copy, keys));
    std::vector<std::uint32_t> back(rays.size());
    unsort(index.data(), index, back.data());
    for (std::size_t i = 0; i < rays.size(); ++i) ASSERT_EQ(back[i], i);
}

TEST(RayOrder, BlocksAreProbedOverTheirWholeLengthAndSortedWhereTheProbeSaysSo) {
    // more than one block, the last one short; the probe says "costly" (the whole block sorted)
    // or "cheap": then the block's first rays are traced as they are, and the rest sorted where
    // the timed part (a sample of the rest traced twice) says so, its answer fixed here
    const std::size_t n = kOrderBlock + kOrderLeast + 77;
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> o(3 * n), d(3 * n);
    for (std::size_t i = 0; i < 3 * n; ++i) o[i] = 8 * u(rng), d[i] = u(rng) + (u(rng) > 0 ? 0.1f : -0.1f);
    const RayBatch batch{o.data(), d.data(), n};
    const Aabb box{{-8, -8, -8}, {8, 8, 8}};
    const double inf = std::numeric_limits<double>::infinity();
    // the timed part's answers fixed: reorder (stall_ns) and interleave (interleave_ns) or not
    struct Case {
        double cost, stall_ns, interleave_ns;
        bool sorted, interleaved;
    };
    const std::size_t last = kOrderLeast + 77, warm = kOrderWarmRays;  // the last block: too few to time
    for (const Case c :
         {Case{0.0, inf, inf, false, false}, Case{0.0, -inf, inf, true, false}, Case{0.0, -inf, -inf, true, true},
          Case{0.0, inf, -inf, false, true}, Case{kOrderNodes, inf, inf, true, true}}) {
        std::vector<std::vector<float>> probed;  // each call's rays, by their origins' y
        std::vector<std::size_t> bases, counts;
        std::vector<bool> was_sorted, interleaved;
        for_each_block(
            batch, box,
            [&](const RayPiece& piece) {
                EXPECT_EQ(piece.count, kWideBatch);
                std::vector<float> y;
                for (std::uint32_t j = 0; j < piece.count; ++j) y.push_back(piece.rays.data()[j].origin.y);
                probed.push_back(y);
                return c.cost;
            },
            [&](std::size_t base, const RayBatch& part, const SortedRays* sorted, WideWalk walk) {
                bases.push_back(base), counts.push_back(part.count), was_sorted.push_back(sorted != nullptr);
                interleaved.push_back(walk == WideWalk::Interleaved);
                EXPECT_EQ(part.origins, o.data() + 3 * base);
                if (!sorted) return;
                std::vector<char> seen(part.count, 0);
                for (std::uint32_t i : sorted->index) {
                    ASSERT_LT(i, part.count);
                    ASSERT_FALSE(seen[i]);
                    seen[i] = 1;
                }
            },
            c.stall_ns, c.interleave_ns);
        const bool whole = c.cost >= kOrderNodes;
        if (whole) {  // costly: sorted and interleaved, the timed answers not asked
            EXPECT_EQ(bases, (std::vector<std::size_t>{0, kOrderBlock}));
            EXPECT_EQ(counts, (std::vector<std::size_t>{kOrderBlock, last}));
            EXPECT_EQ(was_sorted, (std::vector<bool>{true, true}));
            EXPECT_EQ(interleaved, (std::vector<bool>{true, true}));
        } else {  // the first rays as they are, the rest as the timed part says; the last whole
            EXPECT_EQ(bases, (std::vector<std::size_t>{0, warm, kOrderBlock}));
            EXPECT_EQ(counts, (std::vector<std::size_t>{warm, kOrderBlock - warm, last}));
            EXPECT_EQ(was_sorted, (std::vector<bool>{false, c.sorted, false}));
            EXPECT_EQ(interleaved, (std::vector<bool>{false, c.interleaved, false}));
        }
        // each block probed over its whole length, from its first ray to its last; where the nodes
        // do not decide, a sample of the rest, halfway between evenly spread rays, traced twice
        ASSERT_EQ(probed.size(), whole ? 2u : 4u);
        for (std::size_t b = 0; b < 2; ++b) {
            const std::size_t base = b * kOrderBlock, count = b ? last : kOrderBlock, at = b ? probed.size() - 1 : 0;
            const auto y = [&](std::size_t i) { return o[3 * (base + i) + 1]; };
            for (std::uint32_t j = 0; j < kWideBatch; ++j)
                ASSERT_EQ(probed[at][j], y(std::size_t(j) * (count - 1) / (kWideBatch - 1))) << b << " " << j;
        }
        if (whole) continue;
        EXPECT_EQ(probed[1], probed[2]);
        const std::size_t rest = kOrderBlock - warm;
        for (std::uint32_t j = 0; j < kWideBatch; ++j)
            ASSERT_EQ(probed[1][j], o[3 * (warm + (2 * std::size_t(j) + 1) * (rest - 1) / (2 * kWideBatch)) + 1]);
    }
}

/// A batch of random rays (a third with their own tmax) through `bvh`, reordered (whole, or after
/// its first rays: `whole`, whose premise is checked), against the same queries in slices too small
/// to be reordered and against the single walks, bit for bit, on every instruction set path and
/// with 1 and 3 threads; intersect_batch's reordered part through the interleaved walk, or not
/// (`interleaved`).
void expect_each_ray_its_own_hit(const Bvh& bvh, bool whole, bool interleaved, std::size_t count = 4 * kOrderLeast) {
    const WideBvh wide = make_wide(bvh);
    auto rays = random_rays(count, 73);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.5f, 20.0f);
    for (std::size_t i = 0; i < rays.size(); i += 3) rays[i].tmax = u(rng);
    const Arrays arrays(rays);
    // the premise: not in order, and the rays visit enough nodes (over the probe's sample) to be reordered
    ASSERT_FALSE(in_ray_order(arrays.batch(), RayKeys(node_box(bvh.nodes[0]), rays.size())));
    double visited = 0;
    for (std::size_t j = 0; j < kWideBatch; ++j) {
        std::uint32_t v = 0;
        intersect_wide(wide, bvh, rays[j * (rays.size() - 1) / (kWideBatch - 1)], &v);
        visited += v;
    }
    if (whole) ASSERT_GE(visited / kWideBatch, kOrderNodes);
    else ASSERT_LT(visited / kWideBatch, kOrderNodes);
    const std::size_t n = rays.size();
    struct Out {
        std::vector<float> t, u, v;
        std::vector<std::int32_t> prim;
        std::vector<std::uint8_t> kind, blocked;
        std::vector<std::uint32_t> visited;
        explicit Out(std::size_t n) : t(n), u(n), v(n), prim(n), kind(n), blocked(n), visited(n) {}
        HitBatch hits(std::size_t at = 0) {
            return {t.data() + at, prim.data() + at, kind.data() + at,
                    u.data() + at, v.data() + at,    visited.data() + at};
        }
        bool* occluded(std::size_t at = 0) { return reinterpret_cast<bool*>(blocked.data()) + at; }
    };
    const Isa before = active_isa();
    std::uint32_t hits = 0;
    for (Isa isa : supported_isas()) {
        set_isa(isa);
        // the oracle: the same queries in slices too small to be reordered (input order)
        Out slices(n);
        for (std::size_t at = 0; at < n; at += kOrderLeast - 1) {
            RayBatch slice = arrays.batch();
            slice.count = std::min(n - at, kOrderLeast - 1);
            slice.origins += 3 * at, slice.directions += 3 * at, slice.tmax_of += at;
            intersect_batch(bvh, slice, slices.hits(at), Traversal::Wide, 1, &wide);
            occluded_batch(bvh, slice, slices.occluded(at), Traversal::Wide, 1, &wide);
        }
        for (std::uint32_t threads : {1u, 3u}) {
            Out got(n);
            // each query passes its blocks' choice of walk on (wide_kernel.h detail::interleaved_pieces)
            const auto pieces = [] { return detail::interleaved_pieces.load(); };
            const std::uint64_t before_closest = pieces();
            intersect_batch(bvh, arrays.batch(), got.hits(), Traversal::Wide, threads, &wide);
            EXPECT_EQ(pieces() > before_closest, interleaved) << "intersect_batch, " << threads << " threads";
            occluded_batch(bvh, arrays.batch(), got.occluded(), Traversal::Wide, threads, &wide);
            std::uint32_t wrong = 0;
            hits = 0;
            for (std::size_t i = 0; i < n; ++i) {
                std::uint32_t one_visited = 0;
                const Hit one = intersect(bvh, rays[i], Traversal::Stack);  // the binary tree's walk
                intersect_wide(wide, bvh, rays[i], &one_visited);
                const bool miss = one.ref == kNoHit;
                const bool ok = same_bits(got.t[i], slices.t[i]) && same_bits(got.u[i], slices.u[i]) &&
                                same_bits(got.v[i], slices.v[i]) && got.prim[i] == slices.prim[i] &&
                                got.kind[i] == slices.kind[i] && got.visited[i] == slices.visited[i] &&
                                got.blocked[i] == slices.blocked[i] && same_bits(got.t[i], miss ? kInfinity : one.t) &&
                                got.prim[i] == (miss ? -1 : std::int32_t(one.ref & gpu::REF_INDEX_MASK)) &&
                                got.kind[i] == (!miss && (one.ref & gpu::REF_SPHERE_BIT) ? 1 : 0) &&
                                got.visited[i] == one_visited && bool(got.blocked[i]) == !miss;
                if (!ok && ++wrong <= 5) ADD_FAILURE() << isa_name(isa) << ", " << threads << " threads: ray " << i;
                hits += !miss;
            }
            EXPECT_EQ(wrong, 0u);
        }
    }
    set_isa(before);
    // both outcomes common: a batch of all misses or all hits would test little
    EXPECT_GT(hits, rays.size() / 10);
    EXPECT_LT(hits, rays.size() - rays.size() / 10);
}

TEST(RayOrder, ReorderedBatchesGiveEachRayItsOwnHitOnEveryPathAndThreadCount) {
    // many small triangles: random rays visit many nodes, so the whole batch is reordered and
    // interleaved (wide_bvh.h WideWalk)
    const auto scene = test::random_scene(60000, 300, 71);
    expect_each_ray_its_own_hit(build_bvh(scene.view()), true, true);
}

TEST(RayOrder, BatchesReorderedAfterTheirFirstRaysGiveEachRayItsOwnHit) {
    // few, large triangles: the rays visit few nodes, and the timed choice is made "reorder", so
    // each block's first rays go as they are and the rest in ray order, interleaved or alone
    const auto scene = test::random_scene(3000, 600, 72);
    struct Restore {  // also where an assertion returns early: the other tests time as they should
        double before = detail::order_stall_ns.exchange(-std::numeric_limits<double>::infinity());
        double interleave = detail::interleave_stall_ns.load();
        ~Restore() { detail::order_stall_ns = before, detail::interleave_stall_ns = interleave; }
    } restore;
    const Bvh bvh = build_bvh(scene.view());
    // the rest interleaved (wide_bvh.h WideWalk), then one ray after another
    for (const double interleave :
         {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()}) {
        SCOPED_TRACE(interleave < 0 ? "interleaved" : "alone");
        detail::interleave_stall_ns = interleave;
        expect_each_ray_its_own_hit(bvh, false, interleave < 0, kOrderTimedLeast + 1000);
    }
}

TEST(RayOrder, ARefusedRayIsNamedWhereverTheReorderedBatchHasIt) {
    const auto scene = test::random_scene(60000, 0, 71);
    const Bvh bvh = build_bvh(scene.view());
    const WideBvh wide = make_wide(bvh);
    const auto rays = random_rays(3 * kOrderLeast, 75);
    // the probe's first ray, another of its sample ((n - 1) · 5 / 255), and one it does not read
    const std::size_t n = rays.size(), sampled = (n - 1) * 5 / (kWideBatch - 1);
    for (std::size_t bad : {std::size_t(0), sampled, std::size_t(2 * kOrderLeast + 5)}) {
        Arrays arrays(rays);
        arrays.d[3 * bad + 1] = kNaN;
        std::vector<float> t(rays.size());
        std::vector<std::int32_t> prim(rays.size());
        auto blocked = std::make_unique<bool[]>(rays.size());
        for (std::uint32_t threads : {1u, 2u}) {
            const std::string name = "ray " + std::to_string(bad);
            try {
                intersect_batch(bvh, arrays.batch(), {t.data(), prim.data()}, Traversal::Wide, threads, &wide);
                ADD_FAILURE() << "intersect_batch accepted a NaN direction";
            } catch (const std::invalid_argument& e) {
                EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
            }
            try {
                occluded_batch(bvh, arrays.batch(), blocked.get(), Traversal::Wide, threads, &wide);
                ADD_FAILURE() << "occluded_batch accepted a NaN direction";
            } catch (const std::invalid_argument& e) {
                EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
            }
        }
    }
}

TEST(RayOrder, ARefusedRayInALaterBlockIsNamedByItsIndexInTheBatch) {
    test::Scene scene;
    scene.add_triangle({0, 0, 5}, {1, 0, 5}, {0, 1, 5});
    const Bvh bvh = build_bvh(scene.view());
    const WideBvh wide = make_wide(bvh);
    const std::size_t n = kOrderBlock + 1000, bad = kOrderBlock + 123;
    std::vector<float> o(3 * n, 0.25f), d(3 * n, 0.0f), t(n);
    for (std::size_t i = 0; i < n; ++i) d[3 * i + 2] = 1.0f;
    std::vector<std::int32_t> prim(n);
    d[3 * bad + 2] = kNaN;
    auto blocked = std::make_unique<bool[]>(n);
    const RayBatch batch{o.data(), d.data(), n};
    try {
        intersect_batch(bvh, batch, {t.data(), prim.data()}, Traversal::Wide, 2, &wide);
        ADD_FAILURE() << "intersect_batch accepted a NaN direction";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("ray " + std::to_string(bad)), std::string::npos) << e.what();
    }
    try {
        occluded_batch(bvh, batch, blocked.get(), Traversal::Wide, 2, &wide);
        ADD_FAILURE() << "occluded_batch accepted a NaN direction";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("ray " + std::to_string(bad)), std::string::npos) << e.what();
    }
    // and without it, every ray of both blocks hits the triangle, at t = 5 - 0.25
    d[3 * bad + 2] = 1.0f;
    intersect_batch(bvh, batch, {t.data(), prim.data()}, Traversal::Wide, 2, &wide);
    EXPECT_EQ(std::count(t.begin(), t.end(), 4.75f), std::ptrdiff_t(n));
}

/// The bits of rays[0, n)'s floats; with `daz`, as denormals-are-zero reads them (a denormal as a
/// zero of its sign): under it the compilers may flush a field the scalar pass leaves as it is
/// (clang turned `e == 0 ? x : x · 2^-e` into a product by a select, GCC did not), and every later
/// operation reads the two alike.
static std::vector<std::uint32_t> as_read(const Ray* rays, std::uint32_t n, bool daz) {
    std::vector<std::uint32_t> bits(8 * std::size_t(n));
    std::memcpy(bits.data(), rays, bits.size() * sizeof(float));
    if (daz)
        for (std::uint32_t& b : bits)
            if ((b & 0x7f800000u) == 0) b &= 0x80000000u;
    return bits;
}

/// prepare_piece's pass over the caller's rays (ray_batch.h) writes the same piece, bit for bit,
/// on every instruction set path (the AVX2 path eight rays at a time, the rest of the piece ray by
/// ray): rays of every octant, directions from 2^-70 to 2^70 (scaled by a power of two) and 1
/// (not scaled), components of ±0 and denormals, per-ray tmax of 0, a denormal, numbers and
/// infinity, a piece whose length is not a multiple of eight, with and without denormals-are-zero
/// (as_read); a refused ray (NaN) inside an eight or in the tail refuses the piece on every path.
TEST(RayOrder, PiecesAreTheSameBitsOnEveryPath) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::uniform_int_distribution<int> power(-70, 70);
    const std::uint32_t n = kWideBatch - 5;
    std::vector<float> o(3 * n), d(3 * n), tmax(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        const float scale = i % 5 == 0 ? 1.0f : std::ldexp(1.0f, power(rng));
        for (int a = 0; a < 3; ++a) {
            o[3 * i + a] = 100.0f * u(rng);
            d[3 * i + a] = i % 7 == a ? (i % 2 ? -0.0f : 0.0f) : scale * u(rng);
        }
        d[3 * i + 2] = d[3 * i + 2] == 0.0f && d[3 * i] == 0.0f && d[3 * i + 1] == 0.0f ? scale : d[3 * i + 2];
        if (i % 10 == 5) d[3 * i + 1] = 1e-40f;  // a denormal beside a largest component in [0.5, 1) or not
        tmax[i] = i % 11 == 0 ? kInfinity : i % 13 == 0 ? 0.0f : i % 17 == 0 ? 1e-40f : 50.0f * (u(rng) + 1.0f);
    }
    const Isa before = active_isa();
    auto piece_on = [&](Isa isa, const RayBatch& batch, bool& ok) {
        set_isa(isa);
        auto piece = std::make_unique<RayPiece>();
        ok = prepare_piece(batch, 0, batch.count, *piece);
        return piece;
    };
    // also with denormals read as zero (Blender's and other hosts' threads may set it): a field
    // the scalar pass leaves as it is (no scaling needed) must not be multiplied by 1 and flushed
    for (unsigned mode = 0; mode < 4; ++mode) {
        const bool per_ray = mode & 1, daz = mode & 2;
#if defined(__SSE__)
        struct Csr {  // flush-to-zero and denormals-are-zero while set, the caller's mode after
            unsigned before = _mm_getcsr();
            explicit Csr(bool on) { _mm_setcsr(on ? before | 0x8040u : before); }
            ~Csr() { _mm_setcsr(before); }
        } csr(daz);
#else
        if (daz) continue;
#endif
        RayBatch batch{o.data(), d.data(), n};
        batch.tmin = daz ? 1e-40f : 0.25f, batch.tmax = 40.0f;
        if (per_ray) batch.tmax_of = tmax.data();
        bool ok_portable = false;
        const auto portable = piece_on(Isa::Portable, batch, ok_portable);
        ASSERT_TRUE(ok_portable);
        for (Isa isa : supported_isas()) {
            bool ok = false;
            const auto piece = piece_on(isa, batch, ok);
            ASSERT_TRUE(ok) << isa_name(isa);
            ASSERT_EQ(piece->count, n);
            EXPECT_EQ(as_read(piece->rays.data(), n, daz), as_read(portable->rays.data(), n, daz)) << isa_name(isa);
            EXPECT_EQ(std::memcmp(piece->t_scale, portable->t_scale, n * sizeof(float)), 0) << isa_name(isa);
            EXPECT_EQ(std::memcmp(piece->order, portable->order, n * sizeof(std::uint32_t)), 0) << isa_name(isa);
            EXPECT_EQ(std::memcmp(piece->start, portable->start, sizeof portable->start), 0) << isa_name(isa);
        }
        // one refused ray anywhere in the piece (inside an eight, or in the tail) refuses it
        for (std::uint32_t at : {3u, 100u, n - 2}) {
            std::vector<float> bad = d;
            bad[3 * at + 1] = std::nanf("");
            RayBatch refused = batch;
            refused.directions = bad.data();
            for (Isa isa : supported_isas()) {
                bool ok = true;
                piece_on(isa, refused, ok);
                EXPECT_FALSE(ok) << isa_name(isa) << " ray " << at;
            }
        }
    }
    set_isa(before);
}
