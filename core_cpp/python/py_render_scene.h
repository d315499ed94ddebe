// py_render_scene.h — what the Python module keeps per RenderScene, shared by the binding files.
#pragma once
#include <memory>
#include <vector>

#include "bvhlab/prim_ref.h"
#include "bvhlab/ray_record.h"
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

/// The primitives `scene`'s camera rays pass by (their material hides from gpu::RAY_CAMERA, as
/// traverse.glsl `sees` asks), for a record of a pixel's walk (ray_record.h); empty where no
/// material hides. A two-level scene's mesh m's primitives lie from its first_triangle and
/// first_sphere on; `scene` must outlive the result.
inline HiddenPrims hidden_from_camera(const RenderScene& scene) {
    if (!scene.hidden) return {};
    return [&scene](std::uint32_t mesh, std::uint32_t ref) {
        const bool two_level = scene.two_level();
        const std::uint32_t index = ref & gpu::REF_INDEX_MASK;
        const std::uint32_t material =
            is_sphere_ref(ref) ? scene.spheres.at(index + (two_level ? scene.first_sphere.at(mesh) : 0)).material.x
                               : scene.triangles.at(index + (two_level ? scene.first_triangle.at(mesh) : 0)).material;
        return (std::uint32_t(scene.materials.at(material).transparent_ior.w) & gpu::RAY_CAMERA) != 0;
    };
}

}  // namespace bvhlab::python
