// The scene arrays uploaded to device buffers; FrameParams with their device addresses.
#include "vk_scene.h"

namespace bvhlab::vk {
namespace {

template <class Array>
Buffer upload_vector(const Device& device, CommandRunner& runner, const Array& array, bool force_staging) {
    return upload_array(device, runner, array.data(), array.size() * sizeof(array[0]), force_staging);
}

gpu::uvec2 words(VkDeviceAddress a) { return {std::uint32_t(a), std::uint32_t(a >> 32)}; }

}  // namespace

SceneBuffers::SceneBuffers(const Device& device, CommandRunner& runner, const RenderScene& scene, bool force_staging) {
    static const Bvh kNoTree;
    const Bvh& tree = scene.bvh ? *scene.bvh : kNoTree;
    const bool forest = scene.two_level();  // the TLAS and every BLAS (render.h RenderScene)
    nodes_ = forest ? upload_vector(device, runner, scene.forest_nodes, force_staging)
                    : upload_vector(device, runner, tree.nodes, force_staging);
    pairs_ = upload_vector(device, runner, scene.pairs, force_staging);
    prims_ = forest ? upload_vector(device, runner, scene.forest_prims, force_staging)
                    : upload_vector(device, runner, tree.prims, force_staging);
    instances_ = upload_vector(device, runner, scene.instances, force_staging);
    triangles_ = upload_vector(device, runner, scene.triangles, force_staging);
    spheres_ = upload_vector(device, runner, scene.spheres, force_staging);
    materials_ = upload_vector(device, runner, scene.materials, force_staging);
    boxes_ = upload_vector(device, runner, scene.boxes, force_staging);
    summary_.bounds = scene.bounds;
    summary_.order.offset = scene.order.offset;  // the overlay's depth ranges; not the node list
    summary_.tree_height = scene.tree_height;
    summary_.node_count = scene.node_count;
    summary_.ref_count = scene.ref_count;
    summary_.stack_entries = scene.stack_entries;
    summary_.walk_steps = scene.walk_steps;
    summary_.holdout = scene.holdout;
    summary_.hidden = scene.hidden;
    summary_.instances.resize(scene.instances.size());  // make_frame_params counts them (never read)
}

gpu::FrameParams SceneBuffers::frame_params(const RenderSettings& settings) const {
    gpu::FrameParams frame = make_frame_params(summary_, settings);
    frame.addr.nodes = words(nodes_.address());
    frame.addr.pairs = words(pairs_.address());
    frame.addr.prims = words(prims_.address());
    frame.addr.instances = words(instances_.address());
    frame.addr.triangles = words(triangles_.address());
    frame.addr.spheres = words(spheres_.address());
    frame.addr.materials = words(materials_.address());
    frame.addr.boxes = words(boxes_.address());
    return frame;
}

}  // namespace bvhlab::vk
