// The cameras (camera.h) at the level of the frame parameters: vectors of any float magnitude
// normalise (issue 39 #7), bad values are refused by name, and the screen mapping of each
// projection puts the frame where camera.h says (checked against the formulas written here, in
// double precision; the images are checked in tests/python/test_render_cameras.py and against
// Cycles in tests/blender/checks_cameras.py).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "camera_frame.h"  // private to the renderers (core_cpp/src/render)
#include "bvhlab/camera.h"

using namespace bvhlab;

namespace {

gpu::FrameParams frame_of(const Camera& c, std::uint32_t width, std::uint32_t height) {
    gpu::FrameParams f{};
    set_camera_frame(f, c, width, height);
    return f;
}

void expect_refused(Camera c, const std::string& fragment) {
    try {
        validate(c);
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
        return;
    }
    ADD_FAILURE() << "accepted; expected an error containing '" << fragment << "'";
}

}  // namespace

TEST(Camera, VectorsOfAnyMagnitudeNormalise) {
    for (float s : {1e-40f, 1e-38f, 1.0f, 3e38f}) {  // denormal, smallest normal, one, near the largest
        Vec3 u = unit({0, s, 0});
        EXPECT_EQ(u.x, 0.0f);
        EXPECT_EQ(u.y, 1.0f) << s;
        Vec3 d = unit({s, s, 0});
        EXPECT_NEAR(d.x, std::sqrt(0.5f), 1e-7f) << s;
    }
    EXPECT_EQ(length(unit({0, 0, 0})), 0.0f);
    Camera c = look_at({0, -4, 0}, {0, 0, 0});
    c.forward = {0, 1e-40f, 0}, c.up = {0, 0, 1e-40f};
    EXPECT_NO_THROW(validate(c));
    const gpu::FrameParams f = frame_of(c, 4, 4);
    EXPECT_EQ(f.camera_forward.y, 1.0f);
    EXPECT_EQ(f.camera_up.z, 1.0f);
}

TEST(Camera, BadValuesAreRefusedByName) {
    Camera c;
    c.projection = Projection::Orthographic;
    expect_refused(c, "ortho_scale");
    c = Camera{}, c.clip_start = 5, c.clip_end = 5;
    expect_refused(c, "clip_start < clip_end");
    c = Camera{}, c.clip_start = -1;
    expect_refused(c, "clip_start");
    c = Camera{}, c.aperture_radius = 0.1f, c.focus_distance = 0;
    expect_refused(c, "focus_distance");
    c = Camera{}, c.region = {0.5f, 0, 0.5f, 1};
    expect_refused(c, "region");
    c = Camera{}, c.projection = Projection::Equirectangular, c.latitude_max = 95;
    expect_refused(c, "latitude");
    c = Camera{}, c.projection = Projection::Equirectangular, c.longitude_min = -2e5f;
    expect_refused(c, "longitude");
    c = Camera{}, c.projection = Projection::FisheyeEquidistant, c.fisheye_fov_degrees = 1900;
    expect_refused(c, "fisheye_fov");
    c = Camera{}, c.projection = Projection::FisheyeEquidistant, c.fisheye_fov_degrees = 0;
    expect_refused(c, "fisheye_fov");
    // what Blender's settings take and Cycles renders: accepted
    c = Camera{}, c.projection = Projection::FisheyeEquidistant, c.fisheye_fov_degrees = 400;
    EXPECT_NO_THROW(validate(c));
    c = Camera{}, c.projection = Projection::Equirectangular, c.longitude_min = 60, c.longitude_max = -50;
    c.latitude_min = c.latitude_max = 10;
    EXPECT_NO_THROW(validate(c));
    c.longitude_min = -300, c.longitude_max = 300;
    EXPECT_NO_THROW(validate(c));
    c = Camera{}, c.clip_end = std::nanf("");
    expect_refused(c, "NaN");
    EXPECT_THROW(parse_projection("cylindrical"), std::invalid_argument);
    EXPECT_EQ(to_string(parse_projection("fisheye")), "fisheye");
}

TEST(Camera, PerspectiveScreenIsTheShiftedImagePlane) {
    Camera c;  // 45° vertical, the image's aspect (2:1), shifted by fractions of the larger side
    c.shift_x = 0.1f, c.shift_y = -0.05f;
    const gpu::FrameParams f = frame_of(c, 200, 100);
    const double half_h = std::tan(22.5 * M_PI / 180), half_w = 2 * half_h, larger = 2 * half_w;
    EXPECT_NEAR(f.screen.x, -half_w + 0.1 * larger, 1e-6);
    EXPECT_NEAR(f.screen.y, half_h - 0.05 * larger, 1e-6);
    EXPECT_NEAR(f.screen.z, 2 * half_w / 200, 1e-8);
    EXPECT_NEAR(f.screen.w, -2 * half_h / 100, 1e-8);
}

TEST(Camera, OrthographicScaleSpansTheLargerSide) {
    Camera c;
    c.projection = Projection::Orthographic, c.ortho_scale = 6, c.aspect = 0.5f;  // portrait: 6 high, 3 wide
    const gpu::FrameParams f = frame_of(c, 30, 60);
    EXPECT_NEAR(f.screen.x, -1.5, 1e-6);
    EXPECT_NEAR(f.screen.y, 3.0, 1e-6);
    EXPECT_NEAR(f.screen.z, 3.0 / 30, 1e-7);
    EXPECT_NEAR(f.screen.w, -6.0 / 60, 1e-7);
}

TEST(Camera, ARegionIsThatPartOfTheFrame) {
    Camera whole;
    Camera part = whole;
    part.region = {0.25f, 0.5f, 0.75f, 1.0f};  // the middle half across, the bottom half down
    const gpu::FrameParams a = frame_of(whole, 80, 40), b = frame_of(part, 40, 20);
    EXPECT_NEAR(b.screen.x, a.screen.x + 20 * a.screen.z, 1e-6);  // pixel column 20 of the frame
    EXPECT_NEAR(b.screen.y, a.screen.y + 20 * a.screen.w, 1e-6);  // pixel row 20
    EXPECT_NEAR(b.screen.z, a.screen.z, 1e-8);
    EXPECT_NEAR(b.screen.w, a.screen.w, 1e-8);
}

TEST(Camera, PanoramasMapTheUnitSquareAsCycles) {
    Camera c;
    c.projection = Projection::Equirectangular, c.latitude_min = -30, c.latitude_max = 60;
    c.longitude_min = -90, c.longitude_max = 120, c.shift_x = 0.1f;
    const gpu::FrameParams f = frame_of(c, 64, 32);
    EXPECT_NEAR(f.screen.x, 0.1, 1e-7);  // Cycles' view plane [0, 1]² offset by the shift
    EXPECT_NEAR(f.screen.y, 1.0, 1e-7);  // the top row is v = 1
    EXPECT_NEAR(f.screen.z, 1.0 / 64, 1e-9);
    EXPECT_NEAR(f.screen.w, -1.0 / 32, 1e-9);
    // Cycles' equirectangular_range: longitude span and offset, latitude span and offset (radians)
    EXPECT_NEAR(f.panorama.x, -210 * M_PI / 180, 1e-6);
    EXPECT_NEAR(f.panorama.y, 90 * M_PI / 180, 1e-6);
    EXPECT_NEAR(f.panorama.z, -90 * M_PI / 180, 1e-6);
    EXPECT_NEAR(f.panorama.w, M_PI / 2 + 30 * M_PI / 180, 1e-6);
}
