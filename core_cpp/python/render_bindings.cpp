// Bindings of the renderers: the scene in GPU layout, render jobs (sample passes with progress and
// cancel), the CPU reference and the Vulkan renderer, the palettes. Settings arrive as a typed
// RenderSettings (render_settings_bindings.cpp).
#include <chrono>
#include <mutex>
#include <utility>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/unique_ptr.h>
#include <nanobind/stl/vector.h>

#include "bvhlab/owned_mutex.h"
#include "bvhlab/palette.h"
#include "bvhlab/render.h"
#include "bvhlab/render_defaults.h"
#include "py_bvh.h"
#include "py_cancel.h"
#include "py_render_scene.h"
#include "py_two_level.h"
#ifdef BVHLAB_VULKAN
#include "bvhlab/vulkan_renderer.h"
#endif

namespace nb = nanobind;
using namespace nb::literals;
using namespace bvhlab;
using namespace bvhlab::python;

namespace {

using Materials = nb::ndarray<const float, nb::shape<-1, nb::ssize_t(kMaterialFloats)>, nb::c_contig, nb::device::cpu>;
using Indices = nb::ndarray<const std::int32_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Rgba = nb::ndarray<float, nb::shape<-1, -1, 4>, nb::c_contig, nb::device::cpu>;
using Plane = nb::ndarray<float, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using Counters = nb::ndarray<float, nb::shape<-1, -1, gpu::COUNTER_COUNT>, nb::c_contig, nb::device::cpu>;
using Corners = nb::ndarray<const float, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using Depths = nb::ndarray<const std::uint8_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

/// Between the slices of a wait for a job's or the Vulkan renderer's lock (lock_in_slices, a
/// WaitCheck): raises KeyboardInterrupt (or what Python's signal handler raised) out of the wait.
/// Called without the GIL.
void check_signals_while_waiting() {
    if (should_park()) park();  // no GIL to take: the interpreter finishes
    nb::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw nb::python_error();
}

/// A RenderJob used from Python: one call at a time (a job's sums are not for two threads). The
/// lock is only ever waited for without the GIL, and in slices, so that Ctrl-C still reaches a
/// thread waiting for another thread's run. A call from inside the job's own run (its progress
/// callable runs on the thread that holds the lock) raises RuntimeError (ReentrantCall), except
/// the reads that are safe there: the samples and timings of the runs before (issue 39).
struct PyRenderJob {
    std::unique_ptr<RenderJob> job;
    OwnedMutex mutex{"this render job", LockRank::Job};

    template <class F>
    auto locked(F&& f) {
        const LongRelease release;
        const WaitCheck::Scope waiting(&check_signals_while_waiting);  // this job's lock, then the renderer's
        const auto lock = lock_in_slices(mutex);
        return f(*job);
    }

    /// A read that is safe on the thread running the job (in its progress callable: the job
    /// writes these only on that thread, between polls), locked anywhere else.
    template <class F>
    auto read(F&& f) {
        if (mutex.held_by_this_thread()) return f(std::as_const(*job));
        return locked([&](RenderJob& j) { return f(std::as_const(j)); });
    }
};

/// One material index per triangle and per sphere (`of`: which mesh, or empty), else an error naming
/// the counts (a scene's triangles replaced after its tri_material: a render said only "one
/// material index per triangle and per sphere is needed", naming neither: a helper's audit).
void check_material_counts(const Indices& tri_material, const Indices& sphere_material, const GeometryView& g,
                           const std::string& of) {
    auto say = [&](const char* what, std::size_t indices, std::size_t count) {
        throw std::invalid_argument("one material index per " + std::string(what) + " is needed" + of + ": got " +
                                    std::to_string(indices) + " for " + std::to_string(count) + " " + what + "s");
    };
    if (tri_material.shape(0) != g.triangle_count) say("triangle", tri_material.shape(0), g.triangle_count);
    if (sphere_material.shape(0) != g.sphere_count) say("sphere", sphere_material.shape(0), g.sphere_count);
}

RenderScene make_scene(const TreeVersion& tree, const Triangles& tris, const std::optional<Spheres>& spheres,
                       const Materials& materials, const Indices& tri_material, const Indices& sphere_material) {
    GeometryView g = view_of(tris, spheres);
    check_material_counts(tri_material, sphere_material, g, "");
    MaterialView mv{materials.data(), materials.shape(0), tri_material.data(), sphere_material.data()};
    const LongRelease release;
    return make_render_scene(tree.bvh, g, mv);
}

/// The render scene of a two-level tree: mesh k's triangles, spheres (None: none) and material
/// indices in the k-th entry of each list.
PyRenderScene make_two_level_scene(const PyTwoLevel& two, const std::vector<Triangles>& tris,
                                   const std::vector<std::optional<Spheres>>& spheres, const Materials& materials,
                                   const std::vector<Indices>& tri_material,
                                   const std::vector<Indices>& sphere_material) {
    const std::size_t n = two.meshes().size();
    if (tris.size() != n || spheres.size() != n || tri_material.size() != n || sphere_material.size() != n)
        throw std::invalid_argument("one entry per mesh of the two-level tree is needed (" + std::to_string(n) + ")");
    std::vector<RenderMesh> meshes(n);
    for (std::size_t k = 0; k < n; ++k) {
        meshes[k].bvh = &two.meshes()[k]->bvh;
        meshes[k].geometry = view_of(tris[k], spheres[k]);
        check_material_counts(tri_material[k], sphere_material[k], meshes[k].geometry, " of mesh " + std::to_string(k));
        meshes[k].triangle_material = tri_material[k].data();
        meshes[k].sphere_material = sphere_material[k].data();
    }
    MaterialView mv{materials.data(), materials.shape(0), nullptr, nullptr};
    const LongRelease release;
    return PyRenderScene{nullptr, two.meshes(), make_render_scene(two.tlas(), meshes, mv), two.shared_tlas()};
}

/// Traversal::Wide: the wide copy of the flat scene's tree, or of each mesh's of a two-level scene,
/// made once per tree version and kept with it (PyTree::wide), so a viewport's jobs on one tree do
/// not each make their own; `two_level` holds the two-level scene's view while the job is started.
WideTrees wide_trees(const PyRenderScene& s, const RenderSettings& settings, std::optional<TwoLevel>& two_level) {
    if (settings.traversal != Traversal::Wide) return {};
    if (s.scene.two_level()) {
        if (!s.tlas) return {};
        two_level = PyTwoLevel::view_of(*s.tlas, s.meshes, Traversal::Wide);
        return {nullptr, &*two_level};
    }
    if (s.tree && &s.tree->bvh == s.scene.bvh) return {&s.tree->wide(), nullptr};
    for (const TreePtr& m : s.meshes)  // a two-level scene of one identity instance renders flat
        if (&m->bvh == s.scene.bvh) return {&m->wide(), nullptr};
    return {};
}

nb::dict timings_dict(const RenderTimings& t) {
    nb::dict d;
    d["upload_ms"] = t.upload_ms, d["overlay_ms"] = t.overlay_ms, d["trace_ms"] = t.trace_ms;
    d["readback_ms"] = t.readback_ms, d["total_ms"] = t.total_ms, d["device"] = t.device;
    d["dispatches"] = t.dispatches, d["steps_per_dispatch"] = t.steps_per_dispatch;
    d["shadow_rays_opaque"] = t.shadow_rays_opaque, d["shadow_rays_glass"] = t.shadow_rays_glass;
    d["camera_rays_ahead"] = t.camera_rays_ahead;
    return d;
}

/// Runs the job until every pixel has `samples` samples, without the GIL. Ctrl-C (Python's signal
/// handlers) and `progress` (called with the fraction done; a false result stops) are checked
/// between dispatches or budgets of steps. Returns false when `progress` stopped it; raises what
/// Python raised (KeyboardInterrupt, the callable's exception) once the work has stopped.
bool run_job(PyRenderJob& self, std::uint32_t samples, nb::object progress) {
    PyStopCheck check(std::move(progress));
    double fraction = 0.0;
    Cancellation cancel([&] { return check(fraction); });
    bool finished = self.locked([&](RenderJob& job) {
        try {
            job.run(samples, &cancel, &fraction);
            return true;
        } catch (const Cancelled&) { return false; }
    });
    check.rethrow();
    if (finished && check(1.0)) finished = false;  // the final call counts too: its "stop", its exception
    check.rethrow();
    return finished;
}

template <class Array>
float* pixels_of(const std::optional<Array>& a, const RenderSettings& s, const char* what) {
    if (!a) return nullptr;
    if (a->shape(0) != s.height || a->shape(1) != s.width)
        throw std::invalid_argument(std::string(what) + " does not have the render's size");
    return a->data();
}

/// Writes the images of the samples so far into the arrays given; returns (those samples, the
/// timings then), read under the same lock: a run on another thread between the images and a
/// separate read of samples_done made a result say more samples than its images held (9 for 1).
nb::tuple resolve_job(PyRenderJob& self, const std::optional<Rgba>& color, const std::optional<Plane>& depth,
                      const std::optional<Plane>& cost, const std::optional<Rgba>& heat,
                      const std::optional<Counters>& counters) {
    const RenderSettings& s = self.job->settings();
    RenderImages out{pixels_of(color, s, "color"), pixels_of(depth, s, "depth"), pixels_of(cost, s, "cost"),
                     pixels_of(heat, s, "heat"), pixels_of(counters, s, "counters")};
    std::uint32_t samples = 0;
    RenderTimings timings;
    self.locked([&](RenderJob& job) {
        job.resolve(out);
        samples = job.samples_done(), timings = job.timings();
    });
    return nb::make_tuple(samples, timings_dict(timings));
}

void bind_job(nb::module_& m) {
    nb::class_<PyRenderJob>(m, "RenderJob", "A render in sample passes (render.h RenderJob).")
        .def("run", &run_job, "samples"_a, "progress"_a = nb::none(),
             "Traces until every pixel has `samples` samples; False when `progress` said stop.")
        .def("resolve", &resolve_job, "color"_a.noconvert().none(), "depth"_a.noconvert().none(),
             "cost"_a.noconvert().none(), "heat"_a.noconvert().none() = nb::none(),
             "counters"_a.noconvert().none() = nb::none(),
             "Writes the images of the samples so far into the given arrays; (their samples, the timings).")
        .def_prop_ro("samples_done",
                     [](PyRenderJob& j) { return j.read([](const RenderJob& job) { return job.samples_done(); }); })
        .def_prop_ro("samples_per_pixel", [](PyRenderJob& j) { return j.job->samples_per_pixel(); })
        .def_prop_ro("timings", [](PyRenderJob& j) {
            RenderTimings t = j.read([](const RenderJob& job) { return job.timings(); });
            return timings_dict(t);
        });
}

PyRenderJob* wrap(std::unique_ptr<RenderJob> job) { return new PyRenderJob{std::move(job)}; }

/// An n × 3 float array of colour(i) for i < n, owned by the returned numpy array.
template <class Color>
nb::ndarray<nb::numpy, float, nb::ndim<2>> color_array(std::size_t n, const Color& color) {
    auto* out = new float[n * 3];
    for (std::size_t i = 0; i < n; ++i) {
        const gpu::vec3 c = color(i);
        out[3 * i] = c.x, out[3 * i + 1] = c.y, out[3 * i + 2] = c.z;
    }
    nb::capsule owner(out, [](void* p) noexcept { delete[] static_cast<float*>(p); });
    return nb::ndarray<nb::numpy, float, nb::ndim<2>>(out, {n, 3}, owner);
}

void bind_palettes(nb::module_& m) {
    m.def(
        "depth_colors",
        [](const nb::ndarray<const std::uint32_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>& depths) {
            gpu::Palette palette;
            return color_array(depths.shape(0), [&](std::size_t i) { return palette.depth_color(depths.data()[i]); });
        },
        "depths"_a.noconvert(), "Overlay line colour of each tree depth (the shaders' palette).");
    m.def(
        "heat_colors",
        [](const nb::ndarray<const float, nb::ndim<1>, nb::c_contig, nb::device::cpu>& x) {
            gpu::Palette palette;
            return color_array(x.shape(0), [&](std::size_t i) { return palette.heat_color(x.data()[i]); });
        },
        "x"_a.noconvert(), "Heatmap colours of values in [0, 1] (blue → red; the heatmap mode's ramp).");
    m.def(
        "diverging_colors",
        [](const nb::ndarray<const float, nb::ndim<1>, nb::c_contig, nb::device::cpu>& x) {
            gpu::Palette palette;
            return color_array(x.shape(0), [&](std::size_t i) { return palette.diverging_color(x.data()[i]); });
        },
        "x"_a.noconvert(), "Colours of signed values in [-1, 1] (blue → white → red; counter differences).");
}

#ifdef BVHLAB_VULKAN
void bind_vulkan(nb::module_& m) {
    nb::exception<VulkanUnavailable>(m, "VulkanUnavailable", PyExc_RuntimeError);
    m.def("vulkan_loader_available", &vulkan_loader_available);
    m.attr("HAS_VULKAN") = true;
    nb::class_<VulkanRenderer>(m, "VulkanRenderer")
        .def(
            "__init__",
            [](VulkanRenderer* self, const std::string& device, bool validation, bool force_staging) {
                VulkanOptions o;
                o.device = device, o.validation = validation, o.force_staging = force_staging;
                const LongRelease release;
                new (self) VulkanRenderer(o);
            },
            "device"_a, "validation"_a, "force_staging"_a)
        .def_prop_ro("device_name", &VulkanRenderer::device_name)
        .def_prop_ro("device_type", &VulkanRenderer::device_type)
        .def_prop_ro("max_image_dimension", &VulkanRenderer::max_image_dimension)
        .def_prop_ro("bresenham_lines", &VulkanRenderer::bresenham_lines)
        .def_prop_ro("max_line_width", &VulkanRenderer::max_line_width)
        .def("upload",
             [](VulkanRenderer& r, const PyRenderScene& scene) {
                 const LongRelease release;
                 const WaitCheck::Scope waiting(&check_signals_while_waiting);
                 return r.upload(scene.scene);
             })
        .def(
            "start",
            [](VulkanRenderer& r, const RenderSettings& settings) {
                const LongRelease release;
                const WaitCheck::Scope waiting(&check_signals_while_waiting);
                return wrap(r.start(settings));
            },
            "settings"_a, "A RenderJob of the scene uploaded last.")
        .def("take_validation_messages", &VulkanRenderer::take_validation_messages)
        .def_prop_ro("validation_error_count", &VulkanRenderer::validation_error_count);
}
#endif

}  // namespace

void bind_render_settings(nb::module_& m);  // render_settings_bindings.cpp

void bind_render(nb::module_& m) {
    bind_render_settings(m);
    m.def(
        "inside_render_work", [] { return OwnedMutex::highest_held() != LockRank::None; },
        "Whether this thread holds a render job's or renderer's lock (it runs a progress callable of a "
        "render): it must not wait for a lock another thread holds (owned_mutex.h LockRank).");
    nb::exception<RenderIncomplete>(m, "RenderIncomplete", PyExc_RuntimeError);
    nb::class_<PyRenderScene>(m, "RenderScene")
        .def(
            "__init__",
            [](PyRenderScene* self, const PyBvh& bvh, const Triangles& tris, const std::optional<Spheres>& spheres,
               const Materials& materials, const Indices& tri_material, const Indices& sphere_material) {
                TreePtr tree = bvh.current();
                new (self) PyRenderScene{
                    tree, {}, make_scene(*tree, tris, spheres, materials, tri_material, sphere_material), nullptr};
            },
            "bvh"_a, "triangles"_a.noconvert(), "spheres"_a.noconvert().none(), "materials"_a.noconvert(),
            "tri_material"_a.noconvert(), "sphere_material"_a.noconvert())
        .def(
            "__init__",
            [](PyRenderScene* self, const PyTwoLevel& two, const std::vector<Triangles>& tris,
               const std::vector<std::optional<Spheres>>& spheres, const Materials& materials,
               const std::vector<Indices>& tri_material, const std::vector<Indices>& sphere_material) {
                new (self)
                    PyRenderScene(make_two_level_scene(two, tris, spheres, materials, tri_material, sphere_material));
            },
            "two_level"_a, "triangles"_a, "spheres"_a, "materials"_a.noconvert(), "tri_material"_a, "sphere_material"_a,
            "A two-level scene: the TLAS of `two_level` and, per mesh, its triangles, spheres and material indices.")
        .def(
            "with_overlay_boxes",
            [](const PyRenderScene& s, const Corners& lo, const Corners& hi, const Depths& depth) {
                if (hi.shape(0) != lo.shape(0) || depth.shape(0) != lo.shape(0))
                    throw std::invalid_argument("one lo, one hi and one depth per overlay box are needed");
                auto* out = new PyRenderScene{s.tree, s.meshes, {}, s.tlas};
                std::unique_ptr<PyRenderScene> owned(out);
                {
                    const LongRelease release;
                    out->scene = s.scene;  // a copy: renders in flight keep reading `s`
                    set_overlay_boxes(out->scene, lo.data(), hi.data(), depth.data(), lo.shape(0));
                }
                return owned.release();
            },
            "lo"_a.noconvert(), "hi"_a.noconvert(), "depth"_a.noconvert(), nb::rv_policy::take_ownership,
            "A copy whose overlay pass draws these world boxes (sorted by depth; the depth range of the "
            "settings picks among them) instead of the tree's node boxes.")
        .def_prop_ro("overlay_box_count", [](const PyRenderScene& s) { return s.scene.boxes.size(); })
        .def_prop_ro("revision", [](const PyRenderScene& s) { return s.tree ? s.tree->revision : 0; })
        .def_prop_ro("two_level", [](const PyRenderScene& s) { return s.scene.two_level(); })
        .def_prop_ro("height", [](const PyRenderScene& s) { return s.scene.height(); })
        .def(
            "heatmap_scale",
            [](const PyRenderScene& s, const RenderSettings& settings) { return heatmap_scale(s.scene, settings); },
            "settings"_a, "Box tests per primary ray the heatmap shows red with these settings.");
    bind_job(m);
    bind_palettes(m);
    m.def(
        "start_cpu",
        [](const PyRenderScene& scene, const RenderSettings& settings, std::uint32_t threads) {
            const LongRelease release;
            std::optional<TwoLevel> two_level;
            return wrap(start_cpu(scene.scene, settings, threads, wide_trees(scene, settings, two_level)));
        },
        "scene"_a, "settings"_a, "threads"_a = 0, nb::keep_alive<0, 1>(),
        "A RenderJob on the CPU reference (keeps `scene` alive).");
#ifdef BVHLAB_VULKAN
    bind_vulkan(m);
#else
    m.attr("HAS_VULKAN") = false;
#endif
}
