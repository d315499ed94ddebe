// vk_scene.h — the scene on the device (report §3.2, §5.1): one buffer per array — nodes, pairs,
// references, instances (two-level scenes), triangles, spheres, materials, overlay boxes — read by the shaders through buffer
// device addresses in FrameParams, so no storage-buffer binding limit (128 MiB on lavapipe) caps
// the scene size.
#pragma once
#include <cstdint>

#include "bvhlab/render.h"
#include "vk_upload.h"

namespace bvhlab::vk {

class SceneBuffers {
public:
    /// Uploads the arrays; `scene` (and its tree) may be destroyed afterwards.
    SceneBuffers(const Device& device, CommandRunner& runner, const RenderScene& scene, bool force_staging);

    /// make_frame_params for this scene, with the scene's device addresses filled in.
    gpu::FrameParams frame_params(const RenderSettings& settings) const;
    /// What make_frame_params and the step bound read: bounds, depth offsets, node and reference
    /// counts (no arrays, no tree).
    const RenderScene& summary() const { return summary_; }

private:
    Buffer nodes_, pairs_, prims_, instances_, triangles_, spheres_, materials_, boxes_;
    RenderScene summary_;
};

}  // namespace bvhlab::vk
