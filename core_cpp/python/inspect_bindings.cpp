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
#include "py_render_scene.h"

namespace nb = nanobind;
using namespace nb::literals;
using namespace bvhlab;
using namespace bvhlab::python;

namespace {

/// A numpy array that owns `v` (moved, not copied), shaped (len) or (len / width, width).
template <class T>
nb::ndarray<nb::numpy, T> owned_array(std::vector<T>&& v, std::size_t width = 0) {
    auto* held = new std::vector<T>(std::move(v));
    nb::capsule owner(held, [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
    if (width == 0) return nb::ndarray<nb::numpy, T>(held->data(), {held->size()}, owner);
    return nb::ndarray<nb::numpy, T>(held->data(), {held->size() / width, width}, owner);
}

nb::dict py_node_data(const PyBvh& self, unsigned threads) {
    TreePtr tree = self.current();
    NodeData d;
    {
        nb::gil_scoped_release release;
        d = compute_node_data(tree->bvh, threads);
    }
    nb::dict out;
    out["lo"] = owned_array(std::move(d.lo), 3), out["hi"] = owned_array(std::move(d.hi), 3);
    out["depth"] = owned_array(std::move(d.depth)), out["parent"] = owned_array(std::move(d.parent));
    out["left"] = owned_array(std::move(d.left)), out["right"] = owned_array(std::move(d.right));
    out["prim_count"] = owned_array(std::move(d.prim_count)), out["area"] = owned_array(std::move(d.area));
    out["sah_term"] = owned_array(std::move(d.sah_term)), out["subtree_sah"] = owned_array(std::move(d.subtree_sah));
    out["sah_share"] = owned_array(std::move(d.sah_share));
    out["child_overlap"] = owned_array(std::move(d.child_overlap)), out["epo"] = owned_array(std::move(d.epo));
    out["sah_cost"] = d.sah_cost, out["epo_cost"] = d.epo_cost, out["revision"] = tree->revision;
    return out;
}

using Point = std::array<float, 3>;

/// A missed hit's fields as Bvh.intersect writes them (prim -1, kind 0).
void put_hit(nb::dict& out, const TraversalRecord& r) {
    const bool miss = r.hit.ref == kNoHit;
    out["t"] = r.hit.t, out["u"] = r.hit.u, out["v"] = r.hit.v;
    out["prim"] = miss ? -1 : std::int32_t(r.hit.ref & gpu::REF_INDEX_MASK);
    out["kind"] = miss ? 0 : ((r.hit.ref & gpu::REF_SPHERE_BIT) ? 1 : 0);
    out["hit_slot"] = miss ? -1 : std::int64_t(r.hit.slot);
    out["hit_leaf"] = miss ? -1 : std::int64_t(r.hit_leaf);
}

nb::dict py_trace_ray(const PyBvh& self, Point origin, Point direction, float tmin, float tmax,
                      const std::string& traversal) {
    const Traversal mode = parse_traversal(traversal);
    TreePtr tree = self.current();
    Ray ray{{origin[0], origin[1], origin[2]}, {direction[0], direction[1], direction[2]}, tmin, tmax};
    TraversalRecord r;
    {
        nb::gil_scoped_release release;
        r = record_traversal(tree->bvh, ray, mode);
    }
    std::vector<std::uint32_t> refs(r.prim_slots.size());
    for (std::size_t j = 0; j < refs.size(); ++j) refs[j] = tree->bvh.refs[r.prim_slots[j]];
    nb::dict out;
    put_hit(out, r);
    out["box_nodes"] = owned_array(std::move(r.box_nodes)), out["box_hit"] = owned_array(std::move(r.box_hit));
    out["prim_slots"] = owned_array(std::move(r.prim_slots)), out["prim_refs"] = owned_array(std::move(refs));
    out["prim_leaf"] = owned_array(std::move(r.prim_leaf));
    out["prim_box_test"] = owned_array(std::move(r.prim_box_test));
    out["prim_closer"] = owned_array(std::move(r.prim_closer));
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
        nb::gil_scoped_release release;
        bvh = restore_bvh(std::move(saved), g, config.threads);
    }
    return new PyBvh(std::move(bvh));
}

}  // namespace

void bind_inspect(nb::module_& m) {
    nb::class_<PyBvh> bvh = nb::borrow<nb::class_<PyBvh>>(m.attr("Bvh"));
    bvh.def("node_data", &py_node_data, "threads"_a,
            "Every node's data (node_data.h) as a dict of arrays, plus sah_cost and epo_cost.");
    bvh.def("trace_ray", &py_trace_ray, "origin"_a, "direction"_a, "tmin"_a, "tmax"_a, "traversal"_a,
            "One ray's traversal, recorded by the traversal itself (ray_record.h), as a dict.");
    m.attr("NODE_BYTES") = sizeof(BvhNode);
    m.def("restore_bvh", &py_restore, "nodes"_a.noconvert(), "refs"_a.noconvert(), "triangles"_a.noconvert(),
          "spheres"_a.noconvert().none(), "config"_a, "build_ms"_a, "geometry_fingerprint"_a,
          "A saved tree over its geometry, every invariant checked (restore.h).");
    m.def("pixel_ray", &py_pixel_ray, "scene"_a, "settings"_a, "x"_a, "y"_a, "sample"_a,
          "(origin, direction, tmin, tmax) of a pixel's primary ray, from the tracer's camera code (pixel_ray.h).");
}
