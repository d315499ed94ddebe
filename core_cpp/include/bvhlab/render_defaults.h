// render_defaults.h — the one definition of what a render uses when the scene does not say
// (docs/design.md, "Defaults": the two-line case works): the sky, the matte material, the camera that
// frames a scene and the light beside it. Exported to Python (bvhlab.defaults), which reads them.
#pragma once
#include <array>
#include <cstddef>

#include "bvhlab/aabb.h"
#include "bvhlab/vec3.h"

namespace bvhlab {

// In double precision, as Python's floats see them; the renderers use them as float.
/// A soft blue atmosphere (report §2.1: the colour of rays that hit nothing).
inline constexpr std::array<double, 3> kDefaultSkyRgb{0.55, 0.7, 0.9};
/// Matte white: r, g, b, reflective, transparent, ior, holdout, hidden (the rays that do not see it:
/// gpu::RAY_* bits, 0 for none) — the layout of a material row, kMaterialFloats.
inline constexpr std::array<double, 8> kDefaultMaterial{0.8, 0.8, 0.8, 0.0, 0.0, 1.5, 0.0, 0.0};
/// Floats in a material row (MaterialView, bvhlab.Material.as_row).
inline constexpr std::size_t kMaterialFloats = kDefaultMaterial.size();
/// Vertical field of view of the default camera, degrees.
inline constexpr double kDefaultFovY = 45.0;
/// Where the camera stands, and what it looks at, when there is nothing to frame.
inline constexpr std::array<double, 3> kFallbackCameraPosition{0, -5, 2};
inline constexpr std::array<double, 3> kFallbackCameraTarget{0, 0, 0};

inline constexpr Vec3 to_vec3(const std::array<double, 3>& a) { return {float(a[0]), float(a[1]), float(a[2])}; }
inline constexpr Vec3 kDefaultSky = to_vec3(kDefaultSkyRgb);
/// The overlay's line colour when it is not coloured by depth (a warm orange).
inline constexpr std::array<double, 3> kDefaultOverlayRgb{1.0, 0.55, 0.1};
inline constexpr Vec3 kDefaultOverlayColor = to_vec3(kDefaultOverlayRgb);

/// A camera placement in double precision (Python's floats), before it becomes a render Camera.
struct CameraPlacement {
    std::array<double, 3> position, target, up;
    double fov_y_degrees;
};

/// Looks at the centre of `bounds` from the front-upper diagonal (Z up, front = -Y as in Blender),
/// kDefaultFovY vertically, far enough back that the bounding sphere fits the view; the fallback
/// placement when `bounds` is empty.
CameraPlacement default_camera(const Aabb& bounds);

/// A point light a little above and to the right of the camera: 0.3 × the viewing distance (from
/// position to target) along the camera's right and along its up (a direction: its length does
/// not count).
std::array<double, 3> default_light_position(const CameraPlacement& camera);

}  // namespace bvhlab
