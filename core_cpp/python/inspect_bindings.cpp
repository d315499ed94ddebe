// inspect_bindings.cpp — the bindings for inspecting a tree (issue 35): every node's data as
// numpy arrays, made in C++ for all nodes at once; one ray's traversal as recorded by the
// traversal code; a pixel's primary ray from the tracer's camera code.
#include <array>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>

#include "bvhlab/node_data.h"
#include "bvhlab/pixel_ray.h"
#include "bvhlab/ray_record.h"
#include "bvhlab/render_settings.h"
#include "bvhlab/restore.h"
#include "py_bvh.h"
#include "py_cancel.h"
#include "py_record.h"
#include "py_render_scene.h"

namespace nb = nanobind;
using namespace nb::literals;
using namespace bvhlab;
using namespace bvhlab::python;

namespace {

nb::dict py_node_data(const PyBvh& self, unsigned threads, bool epo) {
    TreePtr tree = self.current();
    NodeData d;
    PyStopCheck stop;  // Ctrl-C stops the EPO pass (seconds to minutes on a soup)
    Cancellation cancel([&stop] { return stop(0.0); });
    try {
        const LongRelease release;
        d = compute_node_data(tree->bvh, threads, &cancel, epo);
    } catch (const Cancelled&) {
        stop.rethrow();
        throw;
    }
    nb::dict out = node_data_dict(std::move(d));
    out["revision"] = tree->revision;
    return out;
}

using Point = std::array<float, 3>;

/// `camera_of`: the render scene whose camera rays the record walks as (passing by what they do
/// not see: hidden_from_camera); none: every primitive is seen.
nb::dict py_trace_ray(const PyBvh& self, Point origin, Point direction, float tmin, float tmax,
                      const std::string& traversal, const PyRenderScene* camera_of) {
    const Traversal mode = parse_traversal(traversal);
    TreePtr tree = self.current();
    require_geometry(tree->bvh, "trace_ray");
    Ray ray{{origin[0], origin[1], origin[2]}, {direction[0], direction[1], direction[2]}, tmin, tmax};
    const HiddenPrims hidden = camera_of ? hidden_from_camera(camera_of->scene) : HiddenPrims{};
    if (hidden && mode == Traversal::Wide)
        throw std::invalid_argument("trace_ray: the wide walk does not pass hidden primitives by");
    if (camera_of && camera_of->tree.get() != tree.get())
        throw std::invalid_argument("trace_ray: the render scene is of another version of the tree");
    TraversalRecord r;
    {
        const LongRelease release;
        r = mode == Traversal::Wide ? record_wide_traversal(tree->bvh, tree->wide(), tree->wide_names(), ray)
                                    : record_traversal(tree->bvh, ray, mode, hidden);
    }
    nb::dict out = record_dict(std::move(r), tree->bvh.refs.data());
    out["revision"] = tree->revision;
    return out;
}

nb::tuple py_pixel_ray(const PyRenderScene& scene, const RenderSettings& settings, std::uint32_t x, std::uint32_t y,
                       std::uint32_t sample_index) {
    const Ray r = pixel_ray(scene.scene, settings, x, y, sample_index);
    return nb::make_tuple(Point{r.origin.x, r.origin.y, r.origin.z}, Point{r.dir.x, r.dir.y, r.dir.z}, r.tmin, r.tmax);
}

using NodeBytes = nb::ndarray<const std::uint8_t, nb::shape<-1, sizeof(BvhNode)>, nb::c_contig, nb::device::cpu>;
using Refs = nb::ndarray<const std::uint32_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

PyBvh* py_restore(const NodeBytes& nodes, const Refs& refs, const Triangles& tris,
                  const std::optional<Spheres>& spheres, const BuildConfig& config, double build_ms,
                  std::uint64_t fingerprint) {
    SavedTree saved;
    saved.nodes.resize(nodes.shape(0));
    if (!saved.nodes.empty()) std::memcpy(saved.nodes.data(), nodes.data(), saved.nodes.size() * sizeof(BvhNode));
    saved.refs.assign(refs.data(), refs.data() + refs.shape(0));
    saved.geometry_fingerprint = fingerprint, saved.config = config, saved.build_ms = build_ms;
    GeometryView g = view_of(tris, spheres);
    Bvh bvh;
    {
        const LongRelease release;
        bvh = restore_bvh(std::move(saved), g, config.threads);
    }
    return new PyBvh(std::move(bvh));
}

}  // namespace

void bind_inspect(nb::module_& m) {
    nb::class_<PyBvh> bvh = nb::borrow<nb::class_<PyBvh>>(m.attr("Bvh"));
    bvh.def("node_data", &py_node_data, "threads"_a, "epo"_a = true,
            "Every node's data (node_data.h) as a dict of arrays, plus sah_cost and epo_cost (NaN without epo).");
    bvh.def("trace_ray", &py_trace_ray, "origin"_a, "direction"_a, "tmin"_a, "tmax"_a, "traversal"_a,
            "camera_of"_a = nb::none(),
            "One ray's traversal, recorded by the traversal itself (ray_record.h), as a dict; with camera_of "
            "(a RenderScene of this tree), passing by the primitives its camera rays do not see.");
    m.attr("NODE_BYTES") = sizeof(BvhNode);
    m.def("restore_bvh", &py_restore, "nodes"_a.noconvert(), "refs"_a.noconvert(), "triangles"_a.noconvert(),
          "spheres"_a.noconvert().none(), "config"_a, "build_ms"_a, "geometry_fingerprint"_a,
          "A saved tree over its geometry, every invariant checked (restore.h).");
    m.def("pixel_ray", &py_pixel_ray, "scene"_a, "settings"_a, "x"_a, "y"_a, "sample"_a,
          "(origin, direction, tmin, tmax) of a pixel's primary ray, from the tracer's camera code (pixel_ray.h).");
}
