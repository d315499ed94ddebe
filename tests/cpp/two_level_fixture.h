// two_level_fixture.h — the two-level scene the TLAS tests share (test_tlas, test_tlas_wide):
// meshes, their binary and 8-wide trees, a TLAS over instances of them and the TwoLevel that walks it.
#pragma once
#include <cstdint>
#include <vector>

#include "bvhlab/tlas.h"
#include "bvhlab/wide_bvh.h"
#include "test_scenes.h"
#include "transforms.h"

namespace bvhlab::test {

/// Meshes, their trees (binary and 8-wide), a TLAS over instances of them and the TwoLevel that
/// walks them. `two_level` points into the object itself: make it in place (or where the copy is
/// elided), never copy it.
struct TwoLevelFixture {
    std::vector<Scene> meshes;
    std::vector<Bvh> trees;
    std::vector<WideBvh> wides;
    Tlas tlas;
    TwoLevel two_level;

    /// Builds the trees of `meshes` and the TLAS over the instances: instance i is mesh blas_of[i]
    /// placed by transforms[i].
    void build_two_level(const std::vector<std::uint32_t>& blas_of, const std::vector<Transform>& transforms,
                         const BuildConfig& config = default_tlas_config()) {
        for (const Scene& m : meshes) trees.push_back(build_bvh(m.view()));
        for (const Bvh& t : trees) wides.push_back(make_wide(t));
        std::vector<const Bvh*> blases;
        for (const Bvh& t : trees) blases.push_back(&t);
        tlas = build_tlas(blases, blas_of, transforms, config);
        two_level.tlas = &tlas;
        for (std::size_t b = 0; b < trees.size(); ++b) two_level.blases.push_back({&trees[b], &wides[b]});
    }
};

}  // namespace bvhlab::test
