// render_scene_parts.h — the pieces of a render scene that the flat (render_scene.cpp) and the
// two-level (render_scene_two_level.cpp) makers share.
#pragma once
#include <cstdint>
#include <vector>

#include "bvhlab/render.h"

namespace bvhlab::render_parts {

gpu::vec4 v4(Vec3 v, float w);

/// table ? table[i] : 0, checked to be below `count`; `what` names the primitive in the message.
std::uint32_t material_index(const std::int32_t* table, std::size_t i, std::size_t count, const char* what);

/// The material table in GPU layout (the default material where there is none), checked.
std::vector<gpu::GpuMaterial> gpu_materials(const MaterialView& mv);
/// Whether any of `materials` is a holdout (RenderScene::holdout).
bool any_holdout(const std::vector<gpu::GpuMaterial>& materials);
/// Whether any of `materials` hides from some rays (RenderScene::hidden).
bool any_hidden(const std::vector<gpu::GpuMaterial>& materials);

/// Throws std::invalid_argument unless `bvh` was built (or refitted) over `g`.
void check_tree_matches(const Bvh& bvh, const GeometryView& g);

/// scene.order and scene.boxes: the boxes of the overlay pass, in `bvh`'s depth order (report §3.3.1).
void fill_boxes(RenderScene& scene, const Bvh& bvh);

}  // namespace bvhlab::render_parts
