// Two-level trees (tlas.h): the hits through a TLAS and its shared BLASes equal those of one flat
// tree over the same triangles moved into the world (bad instances and the transforms' arithmetic:
// test_tlas_transforms.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>

#include "bvhlab/coordinate_range.h"
#include "bvhlab/render_settings.h"
#include "bvhlab/two_level_record.h"
#include "traverse_oracles.h"
#include "two_level_fixture.h"

using namespace bvhlab;
using namespace bvhlab::test;

namespace {

/// Meshes, their trees, instances, and the same triangles moved into the world as one flat scene.
struct Instanced : TwoLevelFixture {
    std::vector<std::uint32_t> blas_of;
    std::vector<Transform> transforms;
    Scene flat;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> flat_origin;  ///< flat triangle → (instance, prim)
    Bvh flat_tree;
    WideBvh flat_wide;

    void finish(const BuildConfig& config = default_tlas_config()) {
        build_two_level(blas_of, transforms, config);
        for (std::uint32_t i = 0; i < blas_of.size(); ++i) {
            const GeometryView g = meshes[blas_of[i]].view();
            for (std::uint32_t p = 0; p < g.triangle_count; ++p) {
                const Transform& t = transforms[i];
                flat.add_triangle(t.point(g.vertex(p, 0)), t.point(g.vertex(p, 1)), t.point(g.vertex(p, 2)));
                flat_origin.push_back({i, p});
            }
        }
        flat_tree = build_bvh(flat.view());
        flat_wide = make_wide(flat_tree);
    }
};

Instanced mixed_instances(const BuildConfig& config = default_tlas_config()) {
    Instanced s;
    s.meshes.push_back(random_scene(400, 0, 1));
    s.meshes.push_back(octasphere(6, {5, 5, 5}, 3.0f));
    const float pi = 3.14159265f;
    s.blas_of = {0, 1, 0, 1, 0, 0, 1};
    s.transforms = {
        Transform{},                                                         // identity
        make_transform({0, 0, 1}, pi / 5, {1, 1, 1}, {12, 0, 0}),            // rotation + move
        make_transform({1, 2, 3}, 1.1f, {2.0f, 0.5f, 1.3f}, {-14, 3, 2}),    // non-uniform scale
        make_transform({1, 0, 0}, 0.3f, {-1, 1, 1}, {0, 14, 0}),             // mirrored
        make_transform({0, 1, 0}, 2.0f, {-0.7f, -1.5f, 2.5f}, {4, -12, 6}),  // mirrored, non-uniform
        make_transform({1, 1, 0}, 0.7f, {3, 3, 3}, {30, 30, -5}),            // uniform scale
        make_transform({0, 0, 1}, 0.0f, {1, 1, 1}, {3, 3, 3}),               // overlaps the first ones
    };
    s.finish(config);
    return s;
}

/// Rays from a box around everything towards random points of random world triangles and of space.
std::vector<Ray> rays_at(const Instanced& s, std::uint32_t n, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<Ray> rays;
    const GeometryView g = s.flat.view();
    for (std::uint32_t i = 0; i < n; ++i) {
        const Vec3 origin{-40 + 90 * u(rng), -40 + 90 * u(rng), -40 + 90 * u(rng)};
        Vec3 target{-20 + 60 * u(rng), -20 + 60 * u(rng), -20 + 60 * u(rng)};
        if (i % 4 != 0) {  // most at a triangle's interior
            const std::size_t t = rng() % g.triangle_count;
            float a = 0.1f + 0.8f * u(rng), b = (1 - a) * (0.1f + 0.8f * u(rng));
            target = g.vertex(t, 0) * (1 - a - b) + g.vertex(t, 1) * a + g.vertex(t, 2) * b;
        }
        rays.push_back({origin, target - origin});
    }
    return rays;
}

void expect_same_as_flat(const Instanced& s, Traversal mode, std::uint32_t seed) {
    std::uint32_t disagreements = 0, hits = 0;
    const auto rays = rays_at(s, 4000, seed);
    for (const Ray& ray : rays) {
        const Hit flat =
            mode == Traversal::Wide ? intersect_wide(s.flat_wide, s.flat_tree, ray) : intersect(s.flat_tree, ray, mode);
        const InstanceHit two = intersect_two_level(s.two_level, ray, mode);
        ASSERT_EQ(flat.ref == kNoHit, two.hit.ref == kNoHit && two.instance == kNoHit);
        if (flat.ref == kNoHit) continue;
        ++hits;
        const auto [instance, prim] = s.flat_origin[flat.ref];
        const bool same = instance == two.instance && prim == two.hit.ref;
        // t is in world units in both: the same within float rounding of the moved vertices, which
        // a ray that meets its triangle at a grazing angle magnifies (seed 16: 2.8e-4 of t on the
        // same triangle), so 1e-4 of t counts against the rays' allowance and 1e-2 fails at once
        const bool near = std::fabs(flat.t - two.hit.t) <= 1e-4f * flat.t;
        if (!same || !near) ++disagreements;
        if (same) EXPECT_NEAR(two.hit.t, flat.t, 1e-2f * flat.t);
    }
    // Rays that graze an edge may go either way under different rounding, and grazing rays meet
    // their triangle a little apart; anything more is a bug.
    EXPECT_GT(hits, rays.size() / 2);
    EXPECT_LE(disagreements, rays.size() / 500) << disagreements << " of " << rays.size();
}

}  // namespace

TEST(Tlas, HitsEqualOneFlatTreeOverTheMovedTriangles) {
    const Instanced s = mixed_instances();
    for (Traversal mode : {Traversal::Stack, Traversal::Stackless, Traversal::Wide}) expect_same_as_flat(s, mode, 11);
}

/// TLAS leaves of several instances (a median split, which does not weigh leaves against splits,
/// fills them up to max_leaf_size; every instance in one leaf at 8): each walk reaches every
/// instance of a leaf it enters (Tlas::leaf_instances, whose `last` ends a leaf), as the flat tree
/// finds their triangles.
TEST(Tlas, LeavesOfSeveralInstancesHitAsOneFlatTree) {
    for (std::uint32_t leaf_size : {3u, 8u}) {
        BuildConfig config = default_tlas_config();
        config.method = SplitMethod::Median, config.max_leaf_size = leaf_size;
        const Instanced s = mixed_instances(config);
        std::uint32_t largest = 0;  // the premise: leaves of several instances
        for (const BvhNode& n : s.tlas.tree.nodes)
            if (is_leaf(n)) largest = std::max(largest, leaf_count(n));
        ASSERT_EQ(largest, std::min(leaf_size, 7u));
        for (Traversal mode : {Traversal::Stack, Traversal::Stackless, Traversal::Wide}) {
            expect_same_as_flat(s, mode, 13 + leaf_size);
            for (const Ray& ray : rays_at(s, 1000, 17 + leaf_size)) {  // the any-hit walk: t < tmax exactly
                const InstanceHit two = intersect_two_level(s.two_level, ray, mode);
                Ray limited = ray;
                limited.tmax = two.hit.ref == kNoHit ? 1e4f : two.hit.t;
                ASSERT_FALSE(occluded_two_level(s.two_level, limited, mode));
                if (two.hit.ref == kNoHit) continue;
                limited.tmax = std::nextafter(two.hit.t, kInfinity);
                ASSERT_TRUE(occluded_two_level(s.two_level, limited, mode));
            }
        }
    }
}

/// The recorded two-level walk is the query's: the same hit and nodes_visited, made of the TLAS's
/// box tests and the BLAS walks of the instances entered; the hit lies in the recorded leaves.
TEST(Tlas, RecordedWalkIsTheQuerysWalk) {
    const Instanced s = mixed_instances();
    std::vector<WideNames> names;
    for (std::size_t b = 0; b < s.trees.size(); ++b) names.push_back(name_wide_nodes(s.trees[b], s.wides[b]));
    std::vector<const WideNames*> name_ptrs;
    for (const WideNames& n : names) name_ptrs.push_back(&n);
    for (Traversal mode : {Traversal::Stack, Traversal::Stackless, Traversal::Wide}) {
        int hits = 0;
        for (const Ray& ray : rays_at(s, 400, 21)) {
            std::uint32_t visited = 0;
            const InstanceHit h = intersect_two_level(s.two_level, ray, mode, &visited);
            const TwoLevelRecord r = record_two_level(s.two_level, ray, mode, name_ptrs);
            ASSERT_EQ(r.nodes_visited, visited);
            std::uint32_t sum = std::uint32_t(r.tlas.box_nodes.size());
            for (const TraversalRecord& b : r.blas) sum += b.nodes_visited;
            ASSERT_EQ(sum, visited);
            ASSERT_EQ(r.blas.size(), r.tlas.prim_slots.size());
            ASSERT_EQ(r.hit.instance, h.instance);
            ASSERT_EQ(r.hit.hit.ref, h.hit.ref);
            ASSERT_EQ(r.hit.hit.t, h.hit.t);
            if (h.hit.ref == kNoHit) continue;
            ++hits;
            // the last instance that came closer is the hit's, in the TLAS leaf that holds it
            std::size_t last = r.tlas.prim_closer.size();
            while (last-- > 0 && !r.tlas.prim_closer[last]) {}
            ASSERT_LT(last, r.blas.size());
            ASSERT_EQ(r.tlas.prim_slots[last], h.instance);
            ASSERT_EQ(r.hit_tlas_leaf, r.tlas.prim_leaf[last]);
            const BvhNode& tlas_leaf = s.tlas.tree.nodes[r.hit_tlas_leaf];
            bool holds = false;
            for (std::uint32_t k = tlas_leaf.index; k < tlas_leaf.index + leaf_count(tlas_leaf); ++k)
                holds |= s.tlas.tree.refs[k] == h.instance;
            ASSERT_TRUE(holds);
            ASSERT_EQ(r.blas[last].hit.slot, h.hit.slot);
            ASSERT_EQ(r.blas[last].hit_leaf, r.hit_leaf);
            const Bvh& mesh = s.trees[s.tlas.instances[h.instance].blas];
            const BvhNode& leaf = mesh.nodes[r.hit_leaf];
            if (mode != Traversal::Wide) {
                ASSERT_TRUE(is_leaf(leaf));
                ASSERT_TRUE(leaf.index <= h.hit.slot && h.hit.slot < leaf.index + leaf_count(leaf));
            }
        }
        EXPECT_GT(hits, 200);
    }
}

TEST(Tlas, BatchReportsInstanceAndPrimitive) {
    const Instanced s = mixed_instances();
    const auto rays = rays_at(s, 3000, 4);
    std::vector<float> o, d, t(rays.size()), u(rays.size()), v(rays.size());
    for (const Ray& r : rays)
        o.insert(o.end(), {r.origin.x, r.origin.y, r.origin.z}), d.insert(d.end(), {r.dir.x, r.dir.y, r.dir.z});
    std::vector<std::int32_t> prim(rays.size()), instance(rays.size());
    std::vector<std::uint32_t> visited(rays.size());
    for (std::uint32_t threads : {1u, 3u}) {
        intersect_batch_two_level(s.two_level, {o.data(), d.data(), rays.size()},
                                  {t.data(), prim.data(), nullptr, u.data(), v.data(), visited.data()}, instance.data(),
                                  Traversal::Wide, threads);
        for (std::size_t i = 0; i < rays.size(); ++i) {
            const InstanceHit h = intersect_two_level(s.two_level, rays[i], Traversal::Wide);
            ASSERT_EQ(instance[i], h.hit.ref == kNoHit ? -1 : std::int32_t(h.instance));
            ASSERT_EQ(prim[i], h.hit.ref == kNoHit ? -1 : std::int32_t(h.hit.ref));
            if (h.hit.ref != kNoHit) ASSERT_EQ(t[i], h.hit.t);
        }
    }
}

// The any-hit query through both levels: occluded == the closest hit's t < tmax, for tmax at, just
// after and just before each ray's closest hit (rotated, scaled and mirrored instances), on every
// traversal; the batch on several threads with per-ray tmax gives the same answers.
TEST(Tlas, OccludedEqualsClosestHitBeforeTmax) {
    const Instanced s = mixed_instances();
    auto rays = rays_at(s, 2500, 21);
    for (const Ray& r : random_rays(500, 3)) rays.push_back(r);
    for (Traversal mode : {Traversal::Stack, Traversal::Stackless, Traversal::Wide}) {
        std::uint32_t occluded_count = 0;
        std::vector<float> o, d, tmax;
        std::vector<bool> want;
        for (Ray ray : rays) {
            const float t = intersect_two_level(s.two_level, ray, mode).hit.t;
            for (float limit : {kInfinity, t, std::nextafter(t, kInfinity), std::nextafter(t, 0.0f), 0.5f * t, 8.0f}) {
                if (t == kInfinity && limit != kInfinity && limit != 8.0f) continue;
                ray.tmax = limit;
                const bool expected = t < limit;
                ASSERT_EQ(occluded_two_level(s.two_level, ray, mode), expected) << to_string(mode) << " t " << t;
                occluded_count += expected;
                o.insert(o.end(), {ray.origin.x, ray.origin.y, ray.origin.z});
                d.insert(d.end(), {ray.dir.x, ray.dir.y, ray.dir.z});
                tmax.push_back(limit), want.push_back(expected);
            }
        }
        EXPECT_GT(occluded_count, rays.size());
        RayBatch batch{o.data(), d.data(), tmax.size()};
        batch.tmax_of = tmax.data();
        for (std::uint32_t threads : {1u, 3u}) {
            std::unique_ptr<bool[]> got(new bool[tmax.size()]);
            occluded_batch_two_level(s.two_level, batch, got.get(), mode, threads);
            for (std::size_t i = 0; i < tmax.size(); ++i) ASSERT_EQ(got[i], want[i]) << i;
        }
    }
}

TEST(Tlas, OneIdentityInstanceIsTheFlatTree) {
    const Scene mesh = random_scene(2000, 30, 9);
    const Bvh tree = build_bvh(mesh.view());
    const WideBvh wide = make_wide(tree);
    const Tlas tlas = build_tlas({&tree}, {0}, {Transform{}});
    const TwoLevel scene{&tlas, {{&tree, &wide}}};
    for (const Ray& ray : random_rays(3000, 2)) {
        for (Traversal mode : {Traversal::Stack, Traversal::Stackless, Traversal::Wide}) {
            std::uint32_t flat_visits = 0, two_visits = 0;
            const Hit flat = mode == Traversal::Wide ? intersect_wide(wide, tree, ray, &flat_visits)
                                                     : intersect(tree, ray, mode, &flat_visits);
            const InstanceHit two = intersect_two_level(scene, ray, mode, &two_visits);
            ASSERT_EQ(flat.ref, two.hit.ref);
            ASSERT_EQ(flat.t, two.hit.t);  // bit for bit: no TLAS, no transform
            ASSERT_EQ(flat.u, two.hit.u);
            ASSERT_EQ(flat_visits, two_visits);
            ASSERT_EQ(two.instance, flat.ref == kNoHit ? kNoHit : 0u);
        }
    }
    // The batches are the flat batches themselves, each hit in instance 0
    const auto rays = random_rays(2000, 3);
    const std::size_t n = rays.size();
    std::vector<float> o, d, t[2], u[2], v[2];
    for (const Ray& r : rays)
        o.insert(o.end(), {r.origin.x, r.origin.y, r.origin.z}), d.insert(d.end(), {r.dir.x, r.dir.y, r.dir.z});
    std::vector<std::int32_t> prim[2], instance(n);
    std::vector<std::uint32_t> visited[2];
    for (int k = 0; k < 2; ++k) t[k].resize(n), u[k].resize(n), v[k].resize(n), prim[k].resize(n), visited[k].resize(n);
    auto out = [&](int k) {
        return HitBatch{t[k].data(), prim[k].data(), nullptr, u[k].data(), v[k].data(), visited[k].data()};
    };
    std::unique_ptr<bool[]> flat_blocked(new bool[n]), two_blocked(new bool[n]);
    std::vector<float> tmax(n);
    for (Traversal mode : {Traversal::Stack, Traversal::Stackless, Traversal::Wide}) {
        intersect_batch(tree, {o.data(), d.data(), n}, out(0), mode, 1, &wide);
        intersect_batch_two_level(scene, {o.data(), d.data(), n}, out(1), instance.data(), mode, 1);
        for (std::size_t i = 0; i < n; ++i) {
            ASSERT_EQ(prim[0][i], prim[1][i]);
            ASSERT_EQ(t[0][i], t[1][i]);
            ASSERT_EQ(u[0][i], u[1][i]);
            ASSERT_EQ(visited[0][i], visited[1][i]);
            ASSERT_EQ(instance[i], prim[0][i] < 0 ? -1 : 0);
            tmax[i] = std::isinf(t[0][i]) ? 50.0f : t[0][i] * (i % 2 ? 0.99f : 1.01f);
        }
        RayBatch shadow{o.data(), d.data(), n};
        shadow.tmax_of = tmax.data();
        occluded_batch(tree, shadow, flat_blocked.get(), mode, 1, &wide);
        occluded_batch_two_level(scene, shadow, two_blocked.get(), mode, 1);
        for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(flat_blocked[i], two_blocked[i]);
    }
}

TEST(Tlas, TreeHoldsEveryPlacedInstanceOnceInsideItsBoxes) {
    const Instanced s = mixed_instances();
    std::vector<int> seen(s.tlas.instances.size(), 0);
    const Bvh& tree = s.tlas.tree;
    for (std::uint32_t i = 0; i < tree.node_count(); ++i) {
        const BvhNode& n = tree.nodes[i];
        if (!is_leaf(n)) {
            EXPECT_TRUE(node_box(n).contains(node_box(tree.nodes[i + 1])));
            EXPECT_TRUE(node_box(n).contains(node_box(tree.nodes[n.index])));
            continue;
        }
        EXPECT_EQ(leaf_count(n), 1u);  // default_tlas_config: one instance per leaf
        for (std::uint32_t k = n.index; k < n.index + leaf_count(n); ++k) {
            const std::uint32_t inst = tree.refs[k];
            ++seen.at(inst);
            EXPECT_TRUE(node_box(n).contains(s.tlas.instances[inst].world_box));
        }
    }
    for (int c : seen) EXPECT_EQ(c, 1);
    // every moved vertex lies in its instance's world box
    for (std::size_t f = 0; f < s.flat_origin.size(); ++f) {
        Aabb tri;
        for (int k = 0; k < 3; ++k) tri.grow(s.flat.view().vertex(f, k));
        EXPECT_TRUE(s.tlas.instances[s.flat_origin[f].first].world_box.contains(tri));
    }
}

TEST(Tlas, InstancesOfAnEmptyMeshAreLeftOut) {
    const Scene mesh = random_scene(50, 0, 3);
    const Bvh tree = build_bvh(mesh.view()), empty = build_bvh(GeometryView{});
    const Tlas tlas = build_tlas({&tree, &empty}, {1, 0, 1}, {Transform{}, Transform{}, Transform{}});
    ASSERT_EQ(tlas.tree.refs.size(), 1u);
    EXPECT_EQ(tlas.tree.refs[0], 1u);
    const TwoLevel none{&tlas, {{&tree, nullptr}, {&empty, nullptr}}};
    const Tlas no_instances = build_tlas({&tree}, {}, {});
    const TwoLevel scene{&no_instances, {{&tree, nullptr}}};
    EXPECT_EQ(intersect_two_level(scene, {{0, 0, -5}, {0, 0, 1}}, Traversal::Stack).hit.ref, kNoHit);
    check_two_level(none, Traversal::Stack);
    EXPECT_THROW(check_two_level(none, Traversal::Wide), std::invalid_argument);
}

/// The two-level walk scales the world ray once (WorldRay): a ray as given and its copy scaled as
/// the batch scales it hit the same primitive of the same instance at the same t (bit for bit once
/// the scaled t is scaled back), on every traversal, closest and any hit.
TEST(Tlas, AnUnscaledRayHitsAsItsScaledCopy) {
    const Instanced s = mixed_instances();
    std::uint32_t scaled = 0;
    for (Traversal mode : {Traversal::Stack, Traversal::Stackless, Traversal::Wide}) {
        for (Ray ray : rays_at(s, 1500, 23)) {
            ray.dir = ray.dir * 37.0f;  // largest components from ~4 to ~5,000: every ray rescaled
            Ray copy = ray;
            const float t_scale = scale_ray(copy);
            scaled += t_scale != 1.0f;
            const InstanceHit a = intersect_two_level(s.two_level, ray, mode);
            const InstanceHit b = intersect_two_level(s.two_level, copy, mode);
            ASSERT_EQ(a.instance, b.instance);
            ASSERT_EQ(a.hit.ref, b.hit.ref);
            ASSERT_EQ(a.hit.t, b.hit.t * t_scale);
            ASSERT_EQ(a.hit.u, b.hit.u);
            ray.tmax = copy.tmax = std::isinf(a.hit.t) ? 10.0f : a.hit.t * 0.75f;
            copy.tmax = ray.tmax / t_scale;
            ASSERT_EQ(occluded_two_level(s.two_level, ray, mode), occluded_two_level(s.two_level, copy, mode));
        }
    }
    EXPECT_GT(scaled, 4000u);
}
