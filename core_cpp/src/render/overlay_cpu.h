// overlay_cpu.h — the overlay pass of the CPU reference renderer.
#pragma once
#include <vector>
#include "bvhlab/render.h"

namespace bvhlab {

/// Lines of the boxes in frame.overlay_range, one vec4 per pixel (rgb, camera distance; 0 where no
/// line), as the GPU's overlay pass leaves them in the image for the trace pass.
std::vector<gpu::vec4> rasterize_overlay(const RenderScene& scene, const RenderSettings& settings,
                                         const gpu::FrameParams& frame);

}  // namespace bvhlab
