// Bindings of the renderers: the scene in GPU layout, the CPU reference, the Vulkan renderer.
// Settings arrive as a dict from python/bvhlab/render.py, which checks their types.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "bvhlab/render.h"
#include "py_bvh.h"
#ifdef BVHLAB_VULKAN
#include "bvhlab/vulkan_renderer.h"
#endif

namespace bvhlab::gpu {
/// The colour ramps of shaders/tracer/shade_colors.glsl, for the raster previews and Blender.
struct Palette {
#include "tracer/shade_colors.glsl"
};
}  // namespace bvhlab::gpu

namespace nb = nanobind;
using namespace nb::literals;
using namespace bvhlab;
using namespace bvhlab::python;

namespace {

using Materials = nb::ndarray<const float, nb::shape<-1, 6>, nb::c_contig, nb::device::cpu>;
using Indices = nb::ndarray<const std::int32_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Image = nb::ndarray<float, nb::shape<-1, -1, 4>, nb::c_contig, nb::device::cpu>;

/// A RenderScene and the version of the tree it was made from (kept alive: RenderScene borrows it;
/// a later refit of the Python Bvh makes a new version and leaves this one intact).
struct PyRenderScene {
    TreePtr tree;
    RenderScene scene;
};

Vec3 vec3_of(const nb::handle& seq) {
    auto v = nb::cast<std::vector<float>>(seq);
    if (v.size() != 3) throw std::invalid_argument("expected three numbers");
    return {v[0], v[1], v[2]};
}

RenderSettings settings_from(const nb::dict& d) {
    RenderSettings s;
    s.width = nb::cast<std::uint32_t>(d["width"]);
    s.height = nb::cast<std::uint32_t>(d["height"]);
    s.samples_per_axis = nb::cast<std::uint32_t>(d["samples_per_axis"]);
    s.max_depth = nb::cast<std::uint32_t>(d["max_depth"]);
    s.camera = {vec3_of(d["camera_position"]), vec3_of(d["camera_look_at"]), vec3_of(d["camera_up"]),
                nb::cast<float>(d["camera_fov_y"])};
    s.light = {vec3_of(d["light_position"]), vec3_of(d["light_color"]), nb::cast<float>(d["light_intensity"])};
    s.sky = vec3_of(d["sky"]);
    s.overlay = nb::cast<bool>(d["overlay"]);
    s.overlay_depth_min = nb::cast<std::uint32_t>(d["overlay_depth_min"]);
    s.overlay_depth_max = nb::cast<std::uint32_t>(d["overlay_depth_max"]);
    s.overlay_color_by_depth = nb::cast<bool>(d["overlay_color_by_depth"]);
    s.line_width = nb::cast<float>(d["line_width"]);
    s.traversal = nb::cast<std::uint32_t>(d["traversal"]);
    s.mode = nb::cast<std::uint32_t>(d["mode"]) == gpu::MODE_HEATMAP ? RenderMode::Heatmap : RenderMode::Shade;
    s.heatmap_scale = nb::cast<float>(d["heatmap_scale"]);
    return s;
}

float* image_for(const Image& out, const RenderSettings& s) {
    if (out.shape(0) != s.height || out.shape(1) != s.width)
        throw std::invalid_argument("output image does not have the requested size");
    return out.data();
}

nb::dict timings_dict(const RenderTimings& t) {
    nb::dict d;
    d["upload_ms"] = t.upload_ms, d["overlay_ms"] = t.overlay_ms, d["trace_ms"] = t.trace_ms;
    d["readback_ms"] = t.readback_ms, d["total_ms"] = t.total_ms, d["device"] = t.device;
    return d;
}

RenderScene make_scene(const TreeVersion& tree, const Triangles& tris, const std::optional<Spheres>& spheres,
                       const Materials& materials, const Indices& tri_material, const Indices& sphere_material) {
    GeometryView g = view_of(tris, spheres);
    if (tri_material.shape(0) != g.triangle_count || sphere_material.shape(0) != g.sphere_count)
        throw std::invalid_argument("one material index per triangle and per sphere is needed");
    MaterialView mv{materials.data(), materials.shape(0), tri_material.data(), sphere_material.data()};
    nb::gil_scoped_release release;
    return make_render_scene(tree.bvh, g, mv);
}

}  // namespace

void bind_render(nb::module_& m) {
    nb::class_<PyRenderScene>(m, "RenderScene")
        .def("__init__", [](PyRenderScene* self, const PyBvh& bvh, const Triangles& tris, const std::optional<Spheres>& spheres,
                            const Materials& materials, const Indices& tri_material, const Indices& sphere_material) {
                 TreePtr tree = bvh.current();
                 new (self) PyRenderScene{tree, make_scene(*tree, tris, spheres, materials, tri_material, sphere_material)};
             }, "bvh"_a, "triangles"_a.noconvert(), "spheres"_a.noconvert().none(), "materials"_a.noconvert(),
             "tri_material"_a.noconvert(), "sphere_material"_a.noconvert())
        .def("box_range", [](const PyRenderScene& s, std::uint32_t lo, std::uint32_t hi) {
                 auto r = s.scene.box_range(lo, hi);
                 return nb::make_tuple(r.first, r.second);
             });

    m.def("depth_colors", [](const nb::ndarray<const std::uint32_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>& depths) {
              auto* out = new float[depths.shape(0) * 3];
              gpu::Palette palette;
              for (std::size_t i = 0; i < depths.shape(0); ++i) {
                  gpu::vec3 c = palette.depth_color(depths.data()[i]);
                  out[3 * i] = c.x, out[3 * i + 1] = c.y, out[3 * i + 2] = c.z;
              }
              nb::capsule owner(out, [](void* p) noexcept { delete[] static_cast<float*>(p); });
              return nb::ndarray<nb::numpy, float, nb::ndim<2>>(out, {depths.shape(0), 3}, owner);
          }, "depths"_a.noconvert(), "Overlay line colour of each tree depth (the shaders' palette).");

    m.def("render_cpu", [](const PyRenderScene& scene, const nb::dict& settings, const Image& out, std::uint32_t threads) {
              RenderSettings s = settings_from(settings);
              float* rgba = image_for(out, s);
              RenderTimings t;
              {
                  nb::gil_scoped_release release;
                  t = render_cpu(scene.scene, s, rgba, threads);
              }
              return timings_dict(t);
          }, "scene"_a, "settings"_a, "out"_a.noconvert(), "threads"_a);

#ifdef BVHLAB_VULKAN
    nb::exception<VulkanUnavailable>(m, "VulkanUnavailable", PyExc_RuntimeError);
    m.def("vulkan_loader_available", &vulkan_loader_available);
    m.attr("HAS_VULKAN") = true;
    nb::class_<VulkanRenderer>(m, "VulkanRenderer")
        .def("__init__", [](VulkanRenderer* self, const std::string& device, bool validation, bool force_staging) {
                 VulkanOptions o;
                 o.device = device, o.validation = validation, o.force_staging = force_staging;
                 nb::gil_scoped_release release;
                 new (self) VulkanRenderer(o);
             }, "device"_a, "validation"_a, "force_staging"_a)
        .def_prop_ro("device_name", &VulkanRenderer::device_name)
        .def_prop_ro("device_type", &VulkanRenderer::device_type)
        .def_prop_ro("max_image_dimension", &VulkanRenderer::max_image_dimension)
        .def("upload", [](VulkanRenderer& r, const PyRenderScene& scene) {
                 nb::gil_scoped_release release;
                 return r.upload(scene.scene);
             })
        .def("render", [](VulkanRenderer& r, const nb::dict& settings, const Image& out) {
                 RenderSettings s = settings_from(settings);
                 float* rgba = image_for(out, s);
                 RenderTimings t;
                 {
                     nb::gil_scoped_release release;
                     t = r.render(s, rgba);
                 }
                 return timings_dict(t);
             })
        .def("take_validation_messages", &VulkanRenderer::take_validation_messages)
        .def_prop_ro("validation_error_count", &VulkanRenderer::validation_error_count);
#else
    m.attr("HAS_VULKAN") = false;
#endif
}
