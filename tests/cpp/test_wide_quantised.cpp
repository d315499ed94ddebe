// The quantised wide tree (wide_bvh.h WideLayout::Quantised, WideQNode): every decoded child box
// holds the true box (and is the tightest the 8-bit grid allows), over ordinary and degenerate
// inputs; and the walks through it give the brute force's hits, bit for bit, on every instruction
// set path, single and batched, closest and any hit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/isa.h"
#include "bvhlab/wide_bvh.h"
#include "test_scenes.h"
#include "traverse_oracles.h"

using namespace bvhlab;
using test::brute_force;
using test::supported_isas;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

/// A WideNode of `boxes` (lo, hi pairs), the other slots unused (inverted), child words 100 + k.
WideNode node_of(const std::vector<std::pair<Vec3, Vec3>>& boxes) {
    WideNode n{};
    for (int k = 0; k < 8; ++k) {
        const bool used = k < int(boxes.size());
        const Vec3 lo = used ? boxes[k].first : Vec3{kInf, kInf, kInf};
        const Vec3 hi = used ? boxes[k].second : Vec3{-kInf, -kInf, -kInf};
        n.lo_x[k] = lo.x, n.lo_y[k] = lo.y, n.lo_z[k] = lo.z, n.hi_x[k] = hi.x, n.hi_y[k] = hi.y, n.hi_z[k] = hi.z;
        n.child[k] = used ? 100u + std::uint32_t(k) : 0u;
    }
    return n;
}

/// The checks of one node: used slots as given, child words copied, each decoded plane outside
/// (or on) the true one, and no plane one grid step further in (the tightest that holds).
void expect_holds(const WideNode& n, int count, const char* what) {
    WideQNode q;
    quantise_node(n, q);
    EXPECT_EQ(q.used, (1u << count) - 1u) << what;
    const float* planes = n.lo_x;
    for (int k = 0; k < count; ++k) {
        EXPECT_EQ(q.child[k], n.child[k]) << what;
        for (int a = 0; a < 3; ++a) {
            const float lo = planes[16 * a + k], hi = planes[16 * a + 8 + k];
            const std::uint8_t ql = q.q[16 * a + k], qh = q.q[16 * a + 8 + k];
            const float dl = decode_plane(ql, q.scale[a], q.origin[a]);
            const float dh = decode_plane(qh, q.scale[a], q.origin[a]);
            EXPECT_LE(dl, lo) << what << " slot " << k << " axis " << a;
            EXPECT_GE(dh, hi) << what << " slot " << k << " axis " << a;
            if (ql < 255) EXPECT_GT(decode_plane(ql + 1, q.scale[a], q.origin[a]), lo) << what << " (not tight)";
            if (qh > 0) EXPECT_LT(decode_plane(qh - 1, q.scale[a], q.origin[a]), hi) << what << " (not tight)";
            // a power of two, no subnormal product (the kernels' product is then exact)
            int e = 0;
            EXPECT_EQ(std::frexp(q.scale[a], &e), 0.5f) << what;
            EXPECT_GE(q.scale[a], 0x1p-126f) << what;
        }
    }
}

/// Random boxes of `count` slots, their corners c + [0, extent) · u, some flat on an axis.
std::vector<std::pair<Vec3, Vec3>> random_boxes(std::mt19937& rng, int count, float c, float extent, bool flat) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<std::pair<Vec3, Vec3>> boxes;
    for (int k = 0; k < count; ++k) {
        float lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            const float x = c + extent * u(rng), y = c + extent * u(rng);
            lo[a] = std::min(x, y), hi[a] = flat && (k + a) % 3 == 0 ? lo[a] : std::max(x, y);
        }
        boxes.push_back({{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}});
    }
    return boxes;
}

}  // namespace

TEST(QuantisedNode, DecodedBoxesHoldTheTrueBoxesTightly) {
    std::mt19937 rng(7);
    struct Case {
        const char* what;
        float centre, extent;
    };
    // Sponza-like; far from the origin; tiny near zero; the coordinate range (2^40); and beyond it
    const Case cases[] = {{"sponza-like", -20.0f, 40.0f},   {"far from origin", 1e9f, 1e-2f},
                          {"far, negative", -3e11f, 7.0f},  {"tiny", -1e-30f, 2e-30f},
                          {"subnormal", -1e-42f, 3e-42f},   {"range", -0x1p40f, 0x1p41f},
                          {"1e30", -1e30f, 2e30f},          {"1e30 small", 1e30f, 1e25f},
                          {"near max", -3e38f, 3.4e38f}};
    for (const Case& c : cases)
        for (int count = 1; count <= 8; ++count)
            for (bool flat : {false, true})
                for (int rep = 0; rep < 20; ++rep)
                    expect_holds(node_of(random_boxes(rng, count, c.centre, c.extent, flat)), count, c.what);
    // zero extent on every axis: every slot the same point; and -0 beside +0
    expect_holds(node_of({{{1, 2, 3}, {1, 2, 3}}, {{1, 2, 3}, {1, 2, 3}}}), 2, "one point");
    expect_holds(node_of({{{-0.0f, 0, -0.0f}, {0, 0, 0}}, {{0, -0.0f, 0}, {0, 1, 0}}}), 2, "signed zeros");
    // a huge box beside a tiny one far away in it
    expect_holds(node_of({{{-1e30f, -1e30f, -1e30f}, {1e30f, 1e30f, 1e30f}}, {{5e29f, 5e29f, 5e29f}, {5e29f, 5e29f, 5e29f}}}),
                 2, "huge and point");
}

TEST(QuantisedWide, EveryNodeHoldsTheFloatTreesBoxesAndTheSameLeaves) {
    const auto scene = test::random_scene(3000, 200, 11);
    const Bvh bvh = build_bvh(scene.view());
    const WideBvh f = make_wide(bvh), q = make_wide(bvh, WideLayout::Quantised);
    ASSERT_EQ(q.layout, WideLayout::Quantised);
    EXPECT_EQ(q.node_count, f.node_count);
    EXPECT_EQ(q.packet_count, f.packet_count);
    EXPECT_EQ(q.lines.size(), f.lines.size() - std::size_t(f.node_count) * 2);  // two lines a node fewer
    std::vector<std::pair<std::uint32_t, std::uint32_t>> todo{{0, 0}};
    std::uint32_t nodes = 0;
    while (!todo.empty()) {
        const auto [fl, ql] = todo.back();
        todo.pop_back();
        ++nodes;
        const WideNode& fn = f.node(fl);
        const WideQNode& qn = q.qnode(ql);
        for (int k = 0; k < 8; ++k) {
            const bool used = fn.lo_x[k] <= fn.hi_x[k];
            ASSERT_EQ(bool(qn.used >> k & 1), used);
            if (!used) continue;
            const float* planes = fn.lo_x;
            for (int a = 0; a < 3; ++a) {
                EXPECT_LE(decode_plane(qn.q[16 * a + k], qn.scale[a], qn.origin[a]), planes[16 * a + k]);
                EXPECT_GE(decode_plane(qn.q[16 * a + 8 + k], qn.scale[a], qn.origin[a]), planes[16 * a + 8 + k]);
            }
            ASSERT_EQ(fn.leaf(k), qn.leaf(k));
            if (!fn.leaf(k)) {
                todo.push_back({fn.line(k), qn.line(k)});
                continue;
            }
            for (std::uint32_t a = fn.line(k), b = qn.line(k);; a += kPacketLines, b += kPacketLines) {
                ASSERT_EQ(std::memcmp(&f.packet(a), &q.packet(b), sizeof(PrimPacket)), 0);
                if (!f.packet(a).more) break;
            }
        }
    }
    EXPECT_EQ(nodes, q.node_count);
}

namespace {

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// Closest and any hit through the quantised tree, single and batched, on every instruction set
/// path, against the brute force bit for bit (and the same nodes visited on every path).
void expect_brute_force_hits(const Bvh& bvh, std::vector<Ray> rays, const char* what) {
    const WideBvh wide = make_wide(bvh, WideLayout::Quantised);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const Isa before = active_isa();
    std::vector<Hit> want(rays.size());
    int hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        want[i] = brute_force(bvh, rays[i]);
        hits += want[i].ref != kNoHit;
        if (i % 3 == 0 && want[i].ref != kNoHit) rays[i].tmax = want[i].t * (i % 2 ? 1.0f : 0.5f + u(rng));
        if (i % 3 == 0) want[i] = brute_force(bvh, rays[i]);
    }
    EXPECT_GT(hits, int(rays.size()) / 20) << what << ": too few hits to test anything";
    std::vector<std::uint32_t> visited_first(rays.size());
    for (Isa isa : supported_isas()) {
        set_isa(isa);
        std::vector<Hit> batch(rays.size());
        std::vector<std::uint32_t> batch_visited(rays.size());
        intersect_wide_batch(wide, bvh, rays.data(), rays.size(), batch.data(), batch_visited.data());
        std::vector<char> occluded(rays.size());
        occluded_wide_batch(wide, rays.data(), rays.size(), reinterpret_cast<bool*>(occluded.data()));
        int wrong = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) {
            std::uint32_t visited = 0;
            const Hit h = intersect_wide(wide, bvh, rays[i], &visited);
            if (isa == supported_isas().front()) visited_first[i] = visited;
            // a sphere's u, v come from finish_hit, which the brute force does not call
            const bool sphere = h.ref != kNoHit && (h.ref & gpu::REF_SPHERE_BIT);
            const bool ok = same_bits(h.t, want[i].t) && h.ref == want[i].ref &&
                            (sphere || (same_bits(h.u, want[i].u) && same_bits(h.v, want[i].v))) &&
                            h.slot == want[i].slot && visited == visited_first[i] &&
                            same_bits(batch[i].t, h.t) && batch[i].ref == h.ref && batch_visited[i] == visited &&
                            occluded_wide(wide, rays[i]) == (want[i].t < rays[i].tmax) &&
                            bool(occluded[i]) == (want[i].t < rays[i].tmax);
            if (!ok && ++wrong <= 5)
                ADD_FAILURE() << what << ", " << isa_name(isa) << ": ray " << i << ": t " << h.t << " / " << want[i].t
                              << ", ref " << h.ref << " / " << want[i].ref << ", slot " << h.slot << " / "
                              << want[i].slot << ", visited " << visited << " / " << visited_first[i] << ", batch "
                              << batch[i].t << " " << batch_visited[i] << ", occluded " << occluded_wide(wide, rays[i])
                              << " " << bool(occluded[i]) << " / " << (want[i].t < rays[i].tmax);
        }
    }
    set_isa(before);
}

/// `scene` moved by `offset` and scaled by `scale` (rays likewise).
test::Scene moved(const test::Scene& s, Vec3 offset, float scale) {
    test::Scene out = s;
    for (std::size_t i = 0; i < out.triangles.size(); i += 3)
        for (int a = 0; a < 3; ++a) out.triangles[i + a] = out.triangles[i + a] * scale + (&offset.x)[a];
    for (std::size_t i = 0; i < out.spheres.size(); i += 4) {
        for (int a = 0; a < 3; ++a) out.spheres[i + a] = out.spheres[i + a] * scale + (&offset.x)[a];
        out.spheres[i + 3] *= scale;
    }
    return out;
}

std::vector<Ray> moved_rays(std::vector<Ray> rays, Vec3 offset, float scale) {
    for (Ray& r : rays) r.origin = r.origin * scale + offset;
    return rays;
}

}  // namespace

TEST(QuantisedWide, HitsEqualBruteForceOnEveryPath) {
    const auto scene = test::random_scene(3000, 300, 17);
    for (std::uint32_t leaf : {1u, 4u}) {
        BuildConfig cfg;
        cfg.max_leaf_size = leaf;
        expect_brute_force_hits(build_bvh(scene.view(), cfg), test::random_rays(3000, 5 + leaf), "random scene");
    }
    // far from the origin (coordinates ~2e8, a float's step there 16, small boxes a few steps
    // wide: the grid's origin far off zero), and spread over most of the coordinate range (2^40)
    const auto small = test::random_scene(1500, 100, 19);
    const auto rays = test::random_rays(2000, 23);
    const Vec3 far{2e8f, -3e8f, 1e8f};
    expect_brute_force_hits(build_bvh(moved(small, far, 1000.0f).view()), moved_rays(rays, far, 1000.0f), "far");
    expect_brute_force_hits(build_bvh(moved(small, {}, 5e10f).view()), moved_rays(rays, {}, 5e10f), "huge");
    // flat: every triangle in the plane z = 2 (every node's z extent 0)
    test::Scene flat = small;
    flat.spheres.clear();
    for (std::size_t i = 2; i < flat.triangles.size(); i += 3) flat.triangles[i] = 2.0f;
    expect_brute_force_hits(build_bvh(flat.view()), rays, "flat");
}

TEST(QuantisedWide, RaysOnBoxFacesHitAFlatSquare) {
    // the unit square in z = 0: rays straight down on its edges lie in the boxes' faces, whose
    // quantised planes must still hold them (a zero direction component on a slab plane)
    test::Scene s;
    s.add_triangle({0, 0, 0}, {1, 0, 0}, {1, 1, 0});
    s.add_triangle({0, 0, 0}, {1, 1, 0}, {0, 1, 0});
    for (std::uint32_t leaf : {1u, 2u}) {
        BuildConfig c;
        c.max_leaf_size = leaf;
        const Bvh bvh = build_bvh(s.view(), c);
        const WideBvh wide = make_wide(bvh, WideLayout::Quantised);
        const Isa before = active_isa();
        for (Isa isa : supported_isas()) {
            set_isa(isa);
            for (float x : {0.0f, 0.25f, 0.5f, 1.0f})
                for (float y : {0.0f, 0.5f, 0.75f, 1.0f})
                    for (Vec3 d : {Vec3{0, 0, -1}, Vec3{-0.0f, -0.0f, -2.0f}}) {
                        const Hit h = intersect_wide(wide, bvh, {{x, y, 1}, d});
                        EXPECT_NE(h.ref, kNoHit) << "x " << x << " y " << y;
                        EXPECT_EQ(h.t, 1.0f / std::fabs(d.z));
                    }
            for (Vec3 o : {Vec3{1.0001f, 0.5f, 1}, Vec3{0.5f, -0.0001f, 1}})
                EXPECT_EQ(intersect_wide(wide, bvh, {o, {0, 0, -1}}).ref, kNoHit);
        }
        set_isa(before);
    }
}
