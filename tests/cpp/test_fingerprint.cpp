// The geometry fingerprint (geometry.h): a tree's record of the geometry it was built for, which
// renders and refits check. It must change with any one primitive, with primitives swapped, with
// a triangle's corners swapped and with the counts; it must not depend on the thread count, and
// the build's (taken while the references are made) must equal the standalone one. The bounds
// make_prim_refs takes in the same pass (the root's, for the build) are its references', exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <utility>

#include "bvhlab/bvh.h"
#include "test_scenes.h"

using namespace bvhlab;
using test::Scene;

namespace {

std::uint64_t print(const Scene& s, unsigned threads = 1) { return geometry_fingerprint(s.view(), threads); }

}  // namespace

TEST(Fingerprint, SameForEveryThreadCountAndForTheBuild) {
    // more triangles than one chunk of the passes, and not a multiple of it
    const Scene scene = test::random_scene(70'001, 37, 5);
    const std::uint64_t one = print(scene);
    for (unsigned threads : {2u, 3u, 0u}) EXPECT_EQ(print(scene, threads), one) << threads << " threads";
    for (unsigned threads : {1u, 2u}) {
        PrimRefsSummary summary;
        const BigVector<PrimRef> refs = make_prim_refs(scene.view(), threads, &summary);
        EXPECT_EQ(summary.fingerprint, one) << threads << " threads";
        EXPECT_EQ(refs.size(), scene.view().primitive_count());
        BuildConfig c;
        c.threads = threads;
        EXPECT_EQ(build_bvh(scene.view(), c).fingerprint(), one) << threads << " threads";
    }
}

TEST(Fingerprint, ChangesWithAnyOnePrimitive) {
    const Scene scene = test::random_scene(3'000, 50, 9);
    std::set<std::uint64_t> seen{print(scene)};
    for (std::size_t k : {std::size_t(0), std::size_t(4), std::size_t(1'234 * 9 + 8), scene.triangles.size() - 1}) {
        Scene moved = scene;
        moved.triangles[k] = std::nextafter(moved.triangles[k], INFINITY);  // one ulp of one coordinate
        EXPECT_TRUE(seen.insert(print(moved)).second) << "triangle coordinate " << k;
    }
    for (std::size_t k : {std::size_t(0), std::size_t(3), scene.spheres.size() - 1}) {
        Scene moved = scene;
        moved.spheres[k] = std::nextafter(moved.spheres[k], -INFINITY);
        EXPECT_TRUE(seen.insert(print(moved)).second) << "sphere value " << k;
    }
}

TEST(Fingerprint, ChangesWhenPrimitivesOrCornersSwapOrCountsDiffer) {
    const Scene scene = test::random_scene(500, 20, 3);
    std::set<std::uint64_t> seen{print(scene)};
    Scene swapped = scene;  // triangles 7 and 300 trade places
    for (int c = 0; c < 9; ++c) std::swap(swapped.triangles[7 * 9 + c], swapped.triangles[300 * 9 + c]);
    EXPECT_TRUE(seen.insert(print(swapped)).second);
    Scene corners = scene;  // triangle 11's first and second corners trade places (its winding flips)
    for (int c = 0; c < 3; ++c) std::swap(corners.triangles[11 * 9 + c], corners.triangles[11 * 9 + 3 + c]);
    EXPECT_TRUE(seen.insert(print(corners)).second);
    Scene spheres = scene;  // spheres 2 and 5
    for (int c = 0; c < 4; ++c) std::swap(spheres.spheres[2 * 4 + c], spheres.spheres[5 * 4 + c]);
    EXPECT_TRUE(seen.insert(print(spheres)).second);
    Scene fewer = scene;  // the last triangle dropped
    fewer.triangles.resize(fewer.triangles.size() - 9);
    EXPECT_TRUE(seen.insert(print(fewer)).second);
    Scene none;
    EXPECT_TRUE(seen.insert(print(none)).second);
    Scene one_sphere;
    one_sphere.add_sphere({0, 0, 0}, 1);
    EXPECT_TRUE(seen.insert(print(one_sphere)).second);
}

TEST(PrimRefsSummary, BoundsAreTheReferencesOwn) {
    const Scene scene = test::random_scene(40'003, 29, 8);  // several chunks, spheres after
    for (unsigned threads : {1u, 2u}) {
        PrimRefsSummary summary;
        const BigVector<PrimRef> refs = make_prim_refs(scene.view(), threads, &summary);
        Aabb box, twice;  // brute force: every reference's box and twice-centroid
        for (const PrimRef& r : refs) {
            box.grow(r.box());
            twice.grow(Vec3{r.lo[0] + r.hi[0], r.lo[1] + r.hi[1], r.lo[2] + r.hi[2]});
        }
        for (int a = 0; a < 3; ++a) {
            EXPECT_EQ(summary.box.lo[a], box.lo[a]) << threads << " threads, axis " << a;
            EXPECT_EQ(summary.box.hi[a], box.hi[a]) << threads << " threads, axis " << a;
            EXPECT_EQ(summary.centroids.lo[a], 0.5f * twice.lo[a]) << threads << " threads, axis " << a;
            EXPECT_EQ(summary.centroids.hi[a], 0.5f * twice.hi[a]) << threads << " threads, axis " << a;
        }
    }
    PrimRefsSummary none;
    make_prim_refs(Scene{}.view(), 1, &none);
    EXPECT_TRUE(none.box.empty());
}
