// build_tlas.cpp — the top-level tree over instances (tlas.h): checks, world boxes, and the binned
// SAH build of every tree run over the instances' boxes (build_bvh_over_boxes).
#include <stdexcept>
#include <string>

#include "bvhlab/coordinate_range.h"
#include "bvhlab/tlas.h"

namespace bvhlab {

BuildConfig default_tlas_config() {
    BuildConfig config;
    config.max_leaf_size = 1;
    config.sah_block = 1;
    return config;
}

namespace {

Instance make_instance(const std::vector<const Bvh*>& blases, std::uint32_t blas, const Transform& t,
                       std::size_t index) {
    const std::string what = "instance " + std::to_string(index);
    if (blas >= blases.size())
        throw std::invalid_argument(what + " refers to mesh " + std::to_string(blas) + ", but the scene has " +
                                    std::to_string(blases.size()) + " mesh" + (blases.size() == 1 ? "" : "es"));
    validate_transform(t, what.c_str());
    Instance inst;
    inst.blas = blas;
    inst.object_to_world = t;
    inst.world_to_object = inverse(t);
    inst.identity = t.is_identity();
    const Bvh& tree = *blases[blas];
    if (!tree.empty()) inst.world_box = transform_box(t, node_box(tree.nodes[0]));
    if (!inst.world_box.empty() && !(in_coordinate_range(inst.world_box.lo) && in_coordinate_range(inst.world_box.hi)))
        throw std::invalid_argument(what +
                                    ": the transform moves the mesh outside the supported coordinate range "
                                    "[-2^40, 2^40] (±1.0995e12)");
    return inst;
}

}  // namespace

Tlas build_tlas(const std::vector<const Bvh*>& blases, const std::vector<std::uint32_t>& blas_of,
                const std::vector<Transform>& transforms, const BuildConfig& config) {
    if (blas_of.size() != transforms.size())
        throw std::invalid_argument("one transform per instance: got " + std::to_string(blas_of.size()) +
                                    " instances and " + std::to_string(transforms.size()) + " transforms");
    for (const Bvh* b : blases)
        if (!b) throw std::invalid_argument("a mesh of the scene has no tree");
    Tlas tlas;
    tlas.instances.reserve(blas_of.size());
    for (std::size_t i = 0; i < blas_of.size(); ++i)
        tlas.instances.push_back(make_instance(blases, blas_of[i], transforms[i], i));
    // Instances of empty meshes are not in the tree: box i of the build is instance placed[i].
    std::vector<Aabb> boxes;
    std::vector<std::uint32_t> placed;
    boxes.reserve(tlas.instances.size()), placed.reserve(tlas.instances.size());
    for (std::size_t i = 0; i < tlas.instances.size(); ++i) {
        if (tlas.instances[i].world_box.empty()) continue;
        boxes.push_back(tlas.instances[i].world_box);
        placed.push_back(static_cast<std::uint32_t>(i));
    }
    tlas.tree = build_bvh_over_boxes(boxes.data(), boxes.size(), config);
    for (std::uint32_t& ref : tlas.tree.refs) ref = placed[ref];
    return tlas;
}

}  // namespace bvhlab
