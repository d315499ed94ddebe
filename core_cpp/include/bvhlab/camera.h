// camera.h — the cameras both renderers trace, as Blender's camera data (and Cycles, which renders
// it) define them: perspective, orthographic, and the panoramic equirectangular and fisheye
// equidistant projections; lens shift, image-plane aspect (Blender's pixel aspect), clipping, a
// thin lens for depth of field, and the part of the frame an image shows (Blender's render border).
// The models follow Cycles' camera kernel (intern/cycles/kernel/camera/camera.h and projection.h,
// with the view plane of intern/cycles/blender/camera.cpp blender_camera_viewplane).
#pragma once
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "bvhlab/render_defaults.h"
#include "bvhlab/vec3.h"

namespace bvhlab {

/// How the image maps onto rays.
enum class Projection : std::uint32_t {
    Perspective,         ///< a pinhole: rays from the position through a plane at unit distance
    Orthographic,        ///< parallel rays along forward from a plane through the position
    Equirectangular,     ///< longitude across, latitude up (Cycles' equirectangular_range_to_direction)
    FisheyeEquidistant,  ///< angle from the view axis proportional to the distance from the centre of
                         ///< the frame, the whole frame an ellipse (Cycles' fisheye_to_direction)
};

/// A camera looking along `forward` with `up` above the view axis. The image plane (Blender's view
/// plane) is 2 tan(fov_y/2) high at unit distance (perspective) or ortho_scale along its larger
/// side (orthographic, as Blender's ortho_scale with sensor fit Auto), and `aspect` times as wide
/// as high. Lens shift moves it by fractions of its larger side, as Blender's shift with sensor fit
/// Auto (panoramic: by fractions of the frame's width and height, as Cycles offsets its [0,1]²
/// view plane). Primary rays hit only what lies between clip_start and clip_end: along the view axis
/// (perspective, orthographic), from the position (panoramic), as Cycles clips camera rays.
struct Camera {
    Projection projection = Projection::Perspective;
    Vec3 position = to_vec3(kFallbackCameraPosition);
    Vec3 forward = to_vec3(kFallbackCameraTarget) - to_vec3(kFallbackCameraPosition);  ///< any length > 0
    Vec3 up{0, 0, 1};                           ///< any vector not parallel to forward
    float fov_y_degrees = float(kDefaultFovY);  ///< perspective: vertical field of view
    float ortho_scale = 0;                      ///< orthographic: the image plane's larger side, world units
    float aspect = 0;                           ///< image-plane width / height; 0: the frame's (the image's
                                                ///< width / height, widened by the region)
    float shift_x = 0, shift_y = 0;             ///< lens shift (see above)
    float clip_start = 0;                       ///< >= 0
    float clip_end = std::numeric_limits<float>::infinity();
    float aperture_radius = 0;        ///< thin-lens depth of field: the lens radius in world units (0: a pinhole)
    float focus_distance = 10;        ///< where the thin lens focuses, along the view axis
    float fisheye_fov_degrees = 180;  ///< fisheye: the field of view across the frame's width and height
    float latitude_min = -90, latitude_max = 90;      ///< equirectangular: the frame's bottom and top, degrees
    float longitude_min = -180, longitude_max = 180;  ///< ... its left and right edges (positive to the right)
    /// The part of the frame the image shows, in fractions of the frame from its top-left corner:
    /// x0, y0, x1, y1 (Blender's render border; the whole frame by default).
    std::array<float, 4> region{0, 0, 1, 1};
    /// The image mirrored left to right: the camera's right is -(forward × up), as where Blender's
    /// camera has a world matrix of negative determinant (a scale of -1 on one axis, its own or a
    /// parent's; Cycles keeps the axes' signs as it clears their scale).
    bool mirrored = false;

    bool panoramic() const {
        return projection == Projection::Equirectangular || projection == Projection::FisheyeEquidistant;
    }
};

/// v scaled to unit length without overflow or underflow, denormal components included (the zero
/// vector for zero).
Vec3 unit(Vec3 v);

/// A perspective camera at `position` looking at `target`.
Camera look_at(Vec3 position, Vec3 target, Vec3 up = {0, 0, 1}, float fov_y_degrees = float(kDefaultFovY));

/// Throws std::invalid_argument naming the first bad value of the camera.
void validate(const Camera& camera);

/// Names as the Python API spells them; parse_projection throws std::invalid_argument listing them.
Projection parse_projection(std::string_view name);
std::string to_string(Projection projection);
std::vector<std::string> projection_names();

}  // namespace bvhlab
