// py_two_level.h — `_core.TwoLevel`: a TLAS and the mesh tree versions it was built over
// (tlas_bindings.cpp binds it; render_bindings.cpp makes render scenes of it).
#pragma once
#include <memory>
#include <vector>

#include "bvhlab/tlas.h"
#include "bvhlab/wide_bvh.h"
#include "py_bvh.h"

namespace bvhlab::python {

/// A TLAS and the mesh tree versions it was built over. Immutable once made; the TLAS is shared
/// with the render scenes made of it (their wide traversal walks it).
class PyTwoLevel {
public:
    PyTwoLevel(std::vector<TreePtr> meshes, Tlas tlas)
        : meshes_(std::move(meshes)), tlas_(std::make_shared<const Tlas>(std::move(tlas))) {}

    const Tlas& tlas() const { return *tlas_; }
    const std::shared_ptr<const Tlas>& shared_tlas() const { return tlas_; }
    const std::vector<TreePtr>& meshes() const { return meshes_; }

    /// The query's view of both levels (the wide copies made on first use, once per version).
    TwoLevel view(Traversal mode) const { return view_of(*tlas_, meshes_, mode); }

    /// The view of `tlas` over `meshes` (its trees' versions).
    static TwoLevel view_of(const Tlas& tlas, const std::vector<TreePtr>& meshes, Traversal mode) {
        TwoLevel scene{&tlas, {}};
        for (const TreePtr& m : meshes)
            scene.blases.push_back({&m->bvh, mode == Traversal::Wide ? &m->wide() : nullptr});
        return scene;
    }

private:
    std::vector<TreePtr> meshes_;
    std::shared_ptr<const Tlas> tlas_;
};

}  // namespace bvhlab::python
