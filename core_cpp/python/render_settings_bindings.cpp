// Bindings of what a render is asked to do (render_settings.h) and of its defaults
// (render_defaults.h): a typed RenderSettings with its Camera and PointLight, the enums, the names
// of their values and the limits, so python/bvhlab/render.py and the add-on read them instead of
// retyping them. Values are checked in C++ (validate), once.
#include <array>

#include <nanobind/nanobind.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include "bvhlab/render.h"

namespace nb = nanobind;
using namespace nb::literals;
using namespace bvhlab;

namespace {

using Float3 = std::array<float, 3>;
using Double3 = std::array<double, 3>;

Float3 to_array(Vec3 v) { return {v.x, v.y, v.z}; }

/// A Vec3 member as a read-write property taking any three numbers.
template <class Class, Vec3 Class::* Member>
void vec3_property(nb::class_<Class>& c, const char* name, const char* doc) {
    c.def_prop_rw(
        name, [](const Class& self) { return to_array(self.*Member); },
        [](Class& self, const Double3& v) { self.*Member = to_vec3(v); }, doc);
}

void bind_camera(nb::module_& m) {
    nb::enum_<Projection>(m, "Projection")
        .value("perspective", Projection::Perspective)
        .value("orthographic", Projection::Orthographic)
        .value("equirectangular", Projection::Equirectangular)
        .value("fisheye", Projection::FisheyeEquidistant);
    nb::class_<Camera> camera(m, "Camera", "A camera looking along `forward` (camera.h).");
    camera.def(nb::init<>());
    vec3_property<Camera, &Camera::position>(camera, "position", "where the camera is");
    vec3_property<Camera, &Camera::forward>(camera, "forward", "view direction (any length > 0)");
    vec3_property<Camera, &Camera::up>(camera, "up", "up vector (not parallel to forward)");
    camera.def_rw("projection", &Camera::projection)
        .def_rw("fov_y", &Camera::fov_y_degrees, "perspective: vertical field of view, degrees")
        .def_rw("ortho_scale", &Camera::ortho_scale, "orthographic: the image plane's larger side")
        .def_rw("aspect", &Camera::aspect, "image-plane width / height; 0: the frame's")
        .def_rw("shift_x", &Camera::shift_x, "lens shift in fractions of the image plane's larger side (Blender's)")
        .def_rw("shift_y", &Camera::shift_y)
        .def_rw("clip_start", &Camera::clip_start)
        .def_rw("clip_end", &Camera::clip_end)
        .def_rw("aperture_radius", &Camera::aperture_radius, "thin lens radius, world units (0: no depth of field)")
        .def_rw("focus_distance", &Camera::focus_distance)
        .def_rw("fisheye_fov", &Camera::fisheye_fov_degrees, "fisheye: field of view, degrees")
        .def_rw("latitude_min", &Camera::latitude_min, "equirectangular: degrees")
        .def_rw("latitude_max", &Camera::latitude_max)
        .def_rw("longitude_min", &Camera::longitude_min)
        .def_rw("longitude_max", &Camera::longitude_max)
        .def_rw("region", &Camera::region, "x0, y0, x1, y1: the part of the frame the image shows (from the top left)")
        .def_rw("mirrored", &Camera::mirrored, "the image mirrored left to right (camera.h)")
        .def("validate", [](const Camera& self) { validate(self); }, "Raises ValueError naming the first bad value.");
    m.def("parse_projection", [](const std::string& name) { return parse_projection(name); });
    m.attr("PROJECTIONS") = nb::tuple(nb::cast(projection_names()));

    nb::class_<PointLight> light(m, "PointLight");
    light.def(nb::init<>());
    vec3_property<PointLight, &PointLight::position>(light, "position", "where the light is");
    vec3_property<PointLight, &PointLight::color>(light, "color", "rgb");
    light.def_rw("intensity", &PointLight::intensity);
}

void bind_settings(nb::module_& m) {
    nb::enum_<Traversal>(m, "Traversal")
        .value("stack", Traversal::Stack)
        .value("stackless", Traversal::Stackless)
        .value("wide", Traversal::Wide);
    nb::enum_<RenderMode>(m, "RenderMode").value("shade", RenderMode::Shade).value("heatmap", RenderMode::Heatmap);
    nb::enum_<TraversalCounter>(m, "TraversalCounter", "A traversal counter of a pixel (render_settings.h).")
        .value("box_tests", TraversalCounter::BoxTests)
        .value("box_hits", TraversalCounter::BoxHits)
        .value("prim_tests", TraversalCounter::PrimTests)
        .value("prim_hits", TraversalCounter::PrimHits)
        .value("instance_hits", TraversalCounter::InstanceHits);
    nb::class_<RenderSettings> s(m, "RenderSettings", "What a render is asked to do (render_settings.h).");
    s.def(nb::init<>())
        .def_rw("width", &RenderSettings::width)
        .def_rw("height", &RenderSettings::height)
        .def_rw("samples_per_axis", &RenderSettings::samples_per_axis, "n: n×n samples per pixel")
        .def_rw("max_ray_depth", &RenderSettings::max_ray_depth, "bounces of reflection and refraction")
        .def_rw("camera", &RenderSettings::camera)
        .def_rw("light", &RenderSettings::light)
        .def_rw("overlay", &RenderSettings::overlay)
        .def_rw("overlay_depth_min", &RenderSettings::overlay_depth_min)
        .def_rw("overlay_depth_max", &RenderSettings::overlay_depth_max)
        .def_rw("overlay_color_by_depth", &RenderSettings::overlay_color_by_depth)
        .def_rw("line_width", &RenderSettings::line_width)
        .def_rw("traversal", &RenderSettings::traversal)
        .def_rw("mode", &RenderSettings::mode)
        .def_rw("heatmap_scale", &RenderSettings::heatmap_scale, "box tests at full red; None: 8 × tree height")
        .def_rw("traversal_counters", &RenderSettings::traversal_counters,
                "keep every traversal counter per pixel (RenderJob.resolve's counters)")
        .def_rw("keep_cost", &RenderSettings::keep_cost,
                "keep each pixel's cost (RenderJob.resolve's cost and heat); off, the CPU tracer's wide "
                "traversal traces camera rays eight at a time (the same image)")
        .def_rw("film_transparent", &RenderSettings::film_transparent,
                "Blender's Film ▸ Transparent: alpha = the share of a pixel's camera rays that show something")
        .def_rw("steps_per_dispatch", &RenderSettings::steps_per_dispatch)
        .def_rw("max_steps_per_pixel", &RenderSettings::max_steps_per_pixel)
        .def(
            "validate", [](const RenderSettings& self) { validate(self); },
            "Raises ValueError naming the first bad setting.");
    vec3_property<RenderSettings, &RenderSettings::sky>(s, "sky", "the atmosphere colour (report §2.1)");
    vec3_property<RenderSettings, &RenderSettings::overlay_color>(s, "overlay_color",
                                                                  "the overlay's line colour when not by depth");

    m.def(
        "validate_image_size",
        [](std::uint32_t width, std::uint32_t height, std::uint32_t max_dimension) {
            validate_image_size(width, height, max_dimension);
        },
        "width"_a, "height"_a, "max_dimension"_a = kMaxImageDimension,
        "Raises ValueError for an empty size or one above max_dimension pixels per side.");
    m.def("parse_traversal", [](const std::string& name) { return parse_traversal(name); });
    m.def("parse_render_mode", [](const std::string& name) { return parse_render_mode(name); });
    m.attr("TRAVERSALS") = nb::tuple(nb::cast(traversal_names()));
    m.attr("DEFAULT_TRAVERSAL") = to_string(RenderSettings{}.traversal);  // the one definition: render_settings.h
    m.attr("RENDER_MODES") = nb::tuple(nb::cast(render_mode_names()));
    m.def("parse_traversal_counter", [](const std::string& name) { return parse_traversal_counter(name); });
    m.attr("TRAVERSAL_COUNTERS") = nb::tuple(nb::cast(traversal_counter_names()));
    m.attr("MAX_RAY_DEPTH") = gpu::MAX_RAY_DEPTH;
    m.attr("MAX_SAMPLES_PER_AXIS") = gpu::MAX_SAMPLES_PER_AXIS;
    m.attr("MAX_IMAGE_DIMENSION") = kMaxImageDimension;
    m.attr("MAX_HEATMAP_SCALE") = kMaxHeatmapScale;
    m.attr("MAX_LINE_WIDTH") = kMaxLineWidth;
    m.attr("MAX_STEPS_PER_DISPATCH") = gpu::MAX_STEPS_PER_DISPATCH;
    m.attr("NO_DEPTH") = kNoDepth;
}

void bind_defaults(nb::module_& m) {
    m.attr("DEFAULT_SKY") = nb::tuple(nb::cast(kDefaultSkyRgb));
    m.attr("DEFAULT_MATERIAL") = nb::tuple(nb::cast(kDefaultMaterial));
    nb::dict rays;  // the tracer's rays, as bits of a material's hidden rays (gpu_types.h RAY_*)
    rays["CAMERA"] = gpu::RAY_CAMERA, rays["SHADOW"] = gpu::RAY_SHADOW;
    rays["REFLECTION"] = gpu::RAY_REFLECTION, rays["REFRACTION"] = gpu::RAY_REFRACTION;
    m.attr("RAY_BITS") = rays;
    m.attr("DEFAULT_FOV_Y") = kDefaultFovY;
    m.def(
        "default_camera",
        [](const Double3& lo, const Double3& hi, bool empty) {
            Aabb bounds;
            if (!empty) bounds = {to_vec3(lo), to_vec3(hi)};
            CameraPlacement c = default_camera(bounds);
            return nb::make_tuple(c.position, c.target, c.up, c.fov_y_degrees);
        },
        "lo"_a, "hi"_a, "empty"_a = false,
        "(position, target, up, fov_y) of the camera that frames the box lo..hi (or of the fallback "
        "camera when `empty`).");
    m.def(
        "default_light_position",
        [](const Double3& position, const Double3& target, const Double3& up) {
            return default_light_position({position, target, up, kDefaultFovY});
        },
        "position"_a, "target"_a, "up"_a, "The default point light's position for this camera.");
}

}  // namespace

void bind_render_settings(nb::module_& m) {
    bind_camera(m);
    bind_settings(m);
    bind_defaults(m);
}
