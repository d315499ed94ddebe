// overlay_cpu.h — the overlay pass of the CPU reference renderer.
#pragma once
#include <vector>
#include "bvhlab/render.h"

namespace bvhlab {

/// Lines of the boxes [frame.overlay_first_box, overlay_last_box), frame.overlay_line_width pixels
/// wide, one vec4 per pixel (the line's point relative to the camera, its box's depth + 1; 0 where
/// no line), as the GPU's overlay pass leaves them for the trace pass.
std::vector<gpu::vec4> rasterize_overlay(const RenderScene& scene, const gpu::FrameParams& frame);

}  // namespace bvhlab
