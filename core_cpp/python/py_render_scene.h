// py_render_scene.h — what the Python module keeps per RenderScene, shared by the binding files.
#pragma once
#include <memory>
#include <vector>

#include "bvhlab/render.h"
#include "py_bvh.h"

namespace bvhlab::python {

/// A RenderScene and the version of the tree it was made from (kept alive: RenderScene borrows it;
/// a later refit of the Python Bvh makes a new version and leaves this one intact).
struct PyRenderScene {
    TreePtr tree;                 ///< flat scenes
    std::vector<TreePtr> meshes;  ///< two-level scenes: every mesh's (a one-instance scene borrows one)
    RenderScene scene;
    std::shared_ptr<const Tlas> tlas;  ///< two-level scenes: the TLAS `scene` was made from (the wide traversal's)
};

}  // namespace bvhlab::python
