// py_two_level.h — `_core.TwoLevel`: a TLAS and the mesh tree versions it was built over
// (tlas_bindings.cpp binds it; render_bindings.cpp makes render scenes of it).
#pragma once
#include <vector>

#include "bvhlab/tlas.h"
#include "bvhlab/wide_bvh.h"
#include "py_bvh.h"

namespace bvhlab::python {

/// A TLAS and the mesh tree versions it was built over. Immutable once made.
class PyTwoLevel {
public:
    PyTwoLevel(std::vector<TreePtr> meshes, Tlas tlas) : meshes_(std::move(meshes)), tlas_(std::move(tlas)) {}

    const Tlas& tlas() const { return tlas_; }
    const std::vector<TreePtr>& meshes() const { return meshes_; }

    /// The query's view of both levels (the wide copies made on first use, once per version).
    TwoLevel view(Traversal mode) const {
        TwoLevel scene{&tlas_, {}};
        for (const TreePtr& m : meshes_)
            scene.blases.push_back({&m->bvh, mode == Traversal::Wide ? &m->wide() : nullptr});
        return scene;
    }

private:
    std::vector<TreePtr> meshes_;
    Tlas tlas_;
};

}  // namespace bvhlab::python
