// pixel_ray.h — the primary ray the tracer traces for one sample of one pixel (issue 35), made by
// the tracer's own camera code (shaders/tracer/camera.glsl camera_ray, compiled as C++).
#pragma once
#include <cstdint>

#include "bvhlab/ray.h"
#include "bvhlab/render.h"

namespace bvhlab {

/// The primary ray of sample `sample_index` (0 .. samples_per_axis² - 1) of pixel (x, y), row 0 at
/// the top, with the clipping the tracer gives it (tmin, tmax from clip_start and clip_end; the
/// overlay's lines, which may shorten a primary ray, are not drawn here). Throws
/// std::invalid_argument for a pixel or sample outside the image, bad settings (validate), or a
/// pixel with no ray (outside the fisheye's ellipse).
Ray pixel_ray(const RenderScene& scene, const RenderSettings& settings, std::uint32_t x, std::uint32_t y,
              std::uint32_t sample_index = 0);

}  // namespace bvhlab
