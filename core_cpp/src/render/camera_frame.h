// camera_frame.h — the camera's part of the per-frame parameters (camera.cpp).
#pragma once
#include <cstdint>

#include "bvhlab/camera.h"
#include "gpu_types.h"

namespace bvhlab {

/// Sets the camera fields of `f` (gpu_types.h FrameParams: basis, projection, clipping, thin lens,
/// panoramic ranges) and the screen coordinates of an image of width × height pixels showing the
/// camera's region of its frame.
void set_camera_frame(gpu::FrameParams& f, const Camera& camera, std::uint32_t width, std::uint32_t height);

}  // namespace bvhlab
