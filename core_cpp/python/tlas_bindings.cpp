// tlas_bindings.cpp — two-level trees in Python (tlas.h): `_core.TwoLevel`, a TLAS over instances
// of meshes whose trees are `_core.Bvh`s. It keeps the version of each mesh's tree it was built
// over (py_bvh.h), so a refit of a mesh after the TLAS was built changes neither.
#include <array>
#include <memory>
#include <vector>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "bvhlab/cancel.h"
#include "bvhlab/depth_order.h"
#include "bvhlab/node_data.h"
#include "bvhlab/render_settings.h"
#include "bvhlab/stats.h"
#include "bvhlab/tlas.h"
#include "bvhlab/two_level_record.h"
#include "bvhlab/wide_bvh.h"
#include "py_boxes.h"
#include "py_bvh.h"
#include "py_cancel.h"
#include "py_occluded.h"
#include "py_record.h"
#include "py_render_scene.h"
#include "py_two_level.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace bvhlab::python {
namespace {

using Vectors = nb::ndarray<const float, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using Transforms = nb::ndarray<const float, nb::shape<-1, 3, 4>, nb::c_contig, nb::device::cpu>;
using MeshIndices = nb::ndarray<const std::uint32_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
template <class T>
using Out1D = nb::ndarray<T, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

PyTwoLevel* build_two_level(const std::vector<const PyBvh*>& meshes, const MeshIndices& mesh_of,
                            const Transforms& transforms, const BuildConfig& config) {
    const std::size_t n = mesh_of.shape(0);
    if (transforms.shape(0) != n)
        throw std::invalid_argument("one transform per instance: got " + std::to_string(n) + " instances and " +
                                    std::to_string(transforms.shape(0)) + " transforms");
    std::vector<TreePtr> versions;
    std::vector<const Bvh*> blases;
    for (const PyBvh* m : meshes) {
        if (!m) throw std::invalid_argument("a mesh of the scene has no tree (None)");
        versions.push_back(m->current());
        // a TLAS as a tree (InstancedBvh.tlas) has instance indices for references: walked as a
        // mesh, its leaves read primitives that are not there (a segfault: a helper's audit)
        require_geometry(versions.back()->bvh, ("mesh " + std::to_string(versions.size() - 1)).c_str());
        blases.push_back(&versions.back()->bvh);
    }
    std::vector<std::uint32_t> blas_of(mesh_of.data(), mesh_of.data() + n);
    std::vector<Transform> placed(n);
    for (std::size_t i = 0; i < n; ++i) std::copy_n(transforms.data() + 12 * i, 12, placed[i].m.begin());
    const LongRelease release;
    Tlas tlas = build_tlas(blases, blas_of, placed, config);
    return new PyTwoLevel(std::move(versions), std::move(tlas));
}

void py_check_placement(const PyBvh& tree, std::uint32_t mesh, const MeshIndices& index, const Transforms& transforms) {
    const std::size_t n = index.shape(0);
    if (transforms.shape(0) != n) throw std::invalid_argument("one transform per instance");
    std::vector<Transform> placed(n);
    for (std::size_t i = 0; i < n; ++i) std::copy_n(transforms.data() + 12 * i, 12, placed[i].m.begin());
    TreePtr version = tree.current();
    check_placement(version->bvh, mesh, index.data(), placed.data(), n);
}

void py_intersect(const PyTwoLevel& self, const Vectors& origins, const Vectors& dirs, float tmin, float tmax,
                  const std::string& traversal, std::uint32_t threads, Out1D<float> t, Out1D<std::int32_t> prim,
                  Out1D<std::uint8_t> kind, Out1D<float> u, Out1D<float> v, std::optional<Out1D<std::uint32_t>> visited,
                  Out1D<std::int32_t> instance) {
    const std::size_t n = origins.shape(0);
    if (dirs.shape(0) != n) throw std::invalid_argument("origins and directions differ in length");
    for (std::size_t len : {t.shape(0), prim.shape(0), kind.shape(0), u.shape(0), v.shape(0),
                            visited ? visited->shape(0) : n, instance.shape(0)})
        if (len != n) throw std::invalid_argument("output arrays must have one entry per ray");
    const Traversal mode = parse_traversal(traversal);
    RayBatch rays{origins.data(), dirs.data(), n, tmin, tmax};
    HitBatch hits{t.data(), prim.data(), kind.data(), u.data(), v.data(), visited ? visited->data() : nullptr};
    PyStopCheck stop;  // Ctrl-C stops a long batch
    Cancellation cancel([&stop] { return stop(0.0); });
    try {
        const LongRelease release;
        intersect_batch_two_level(self.view(mode), rays, hits, instance.data(), mode, threads, &cancel);
    } catch (const Cancelled&) {
        stop.rethrow();
        throw;
    }
}

void py_occluded(const PyTwoLevel& self, const Vectors& origins, const Vectors& dirs, float tmin, float tmax,
                 const std::optional<RayFloats>& tmax_of, const std::string& traversal, std::uint32_t threads,
                 Occluded out) {
    const RayBatch rays = occluded_rays(origins, dirs, tmin, tmax, tmax_of, out);
    const Traversal mode = parse_traversal(traversal);
    run_released([&](Cancellation* cancel) {
        occluded_batch_two_level(self.view(mode), rays, out.data(), mode, threads, cancel);
    });
}

using Point = std::array<float, 3>;

/// One ray's two-level walk (two_level_record.h) as a dict: "tlas" (its record, whose primitives
/// are the instances entered), "blas" (a record per instance entered), the hit and its instance.
nb::dict py_trace_ray(const PyTwoLevel& self, Point origin, Point direction, float tmin, float tmax,
                      const std::string& traversal, const PyRenderScene* camera_of) {
    const Traversal mode = parse_traversal(traversal);
    const HiddenPrims hidden = camera_of ? hidden_from_camera(camera_of->scene) : HiddenPrims{};
    if (camera_of && (camera_of->tlas != self.shared_tlas() || camera_of->meshes != self.meshes()))
        throw std::invalid_argument("trace_ray: the render scene is of another two-level scene");
    Ray ray{{origin[0], origin[1], origin[2]}, {direction[0], direction[1], direction[2]}, tmin, tmax};
    TwoLevelRecord r;
    {
        const LongRelease release;
        std::vector<const WideNames*> names;
        if (mode == Traversal::Wide)
            for (const TreePtr& m : self.meshes()) names.push_back(&m->wide_names());
        r = record_two_level(self.view(mode), ray, mode, names, hidden);
    }
    nb::dict out;
    const bool miss = r.hit.hit.ref == kNoHit;
    out["instance"] = miss ? -1 : std::int64_t(r.hit.instance);
    out["hit_tlas_leaf"] = miss || r.hit_tlas_leaf == kNoHit ? -1 : std::int64_t(r.hit_tlas_leaf);
    out["nodes_visited"] = r.nodes_visited;
    nb::list blas;
    for (std::size_t j = 0; j < r.blas.size(); ++j) {
        const std::uint32_t instance = r.tlas.prim_slots[j];
        const Bvh& mesh = self.meshes()[self.tlas().instances[instance].blas]->bvh;
        blas.append(record_dict(std::move(r.blas[j]), mesh.refs.data()));
    }
    out["blas"] = blas;
    out["tlas"] = record_dict(std::move(r.tlas), nullptr);
    return out;
}

/// The TLAS's node data (node_data.h; EPO 0: it holds instances, not geometry) as Bvh.node_data's
/// dict, with `leaf_first` (per node: a leaf's first slot in `refs`, else -1) and `refs` (the
/// instances in leaf order).
nb::dict py_tlas_node_data(const PyTwoLevel& self) {
    const Bvh& tree = self.tlas().tree;
    NodeData d = compute_node_data(tree, 1);
    nb::dict out = node_data_dict(std::move(d));
    std::vector<std::int32_t> leaf_first(tree.node_count(), -1);
    for (std::uint32_t i = 0; i < tree.node_count(); ++i)
        if (is_leaf(tree.nodes[i])) leaf_first[i] = std::int32_t(tree.nodes[i].index);
    out["leaf_first"] = owned_array(std::move(leaf_first));
    out["refs"] = owned_array(std::vector<std::uint32_t>(tree.refs.begin(), tree.refs.end()));
    return out;
}

nb::dict tlas_stats(const PyTwoLevel& self) {
    const Tlas& tlas = self.tlas();
    const BvhStats s = compute_stats(tlas.tree);
    nb::dict d;
    d["instances"] = tlas.instances.size(), d["meshes"] = self.meshes().size();
    d["tlas_nodes"] = s.nodes, d["tlas_height"] = s.height, d["tlas_sah_cost"] = s.sah_cost;
    d["tlas_build_ms"] = tlas.tree.build_ms;
    // the binary tree, its wide copy, the instances and their copies in leaf order
    d["tlas_memory_bytes"] = s.memory_bytes + tlas.wide.lines.size() * sizeof(WideLine) +
                             tlas.instances.size() * sizeof(Instance) +
                             tlas.leaf_instances.size() * sizeof(LeafInstance);
    return d;
}

}  // namespace
}  // namespace bvhlab::python

void bind_tlas(nb::module_& m) {
    using namespace bvhlab;
    using namespace bvhlab::python;
    nb::class_<PyTwoLevel>(m, "TwoLevel")
        .def("stats", &tlas_stats)
        .def_prop_ro("instance_count", [](const PyTwoLevel& s) { return s.tlas().instances.size(); })
        .def(
            "tlas_tree", [](const PyTwoLevel& s) { return new PyBvh(s.tlas().tree); }, nb::rv_policy::take_ownership,
            "A copy of the TLAS as a tree (its references are instance indices, it has no geometry).")
        .def(
            "world_boxes",
            [](const PyTwoLevel& s) {
                const auto& inst = s.tlas().instances;
                auto* lo = new float[3 * inst.size()];
                auto* hi = new float[3 * inst.size()];
                for (std::size_t i = 0; i < inst.size(); ++i)
                    for (int k = 0; k < 3; ++k)
                        lo[3 * i + k] = inst[i].world_box.lo[k], hi[3 * i + k] = inst[i].world_box.hi[k];
                auto owned = [](float* p) {
                    return nb::capsule(p, [](void* q) noexcept { delete[] static_cast<float*>(q); });
                };
                return nb::make_tuple(nb::ndarray<nb::numpy, float, nb::ndim<2>>(lo, {inst.size(), 3}, owned(lo)),
                                      nb::ndarray<nb::numpy, float, nb::ndim<2>>(hi, {inst.size(), 3}, owned(hi)));
            },
            "(lo (N,3), hi (N,3)): each instance's world box (empty, lo > hi, for an empty mesh)")
        .def(
            "tlas_boxes",
            [](const PyTwoLevel& s, std::uint32_t depth_min, std::uint32_t depth_max, bool leaves_only) {
                const Bvh& tree = s.tlas().tree;
                return boxes_by_depth(tree, make_depth_order(tree), depth_min, depth_max, leaves_only);
            },
            "depth_min"_a, "depth_max"_a, "leaves_only"_a,
            "The TLAS's node boxes by depth, as Bvh.boxes gives a tree's: (lo (K,3), hi (K,3), depth (K,))")
        .def("intersect", &py_intersect, "origins"_a.noconvert(), "directions"_a.noconvert(), "tmin"_a, "tmax"_a,
             "traversal"_a, "threads"_a, "t"_a.noconvert(), "prim"_a.noconvert(), "kind"_a.noconvert(),
             "u"_a.noconvert(), "v"_a.noconvert(), "visited"_a.noconvert().none(), "instance"_a.noconvert())
        .def("tlas_node_data", &py_tlas_node_data, "The TLAS's node data as a dict (Bvh.node_data's, EPO 0).")
        .def("trace_ray", &py_trace_ray, "origin"_a, "direction"_a, "tmin"_a, "tmax"_a, "traversal"_a,
             "camera_of"_a = nb::none(),
             "One ray's walk through both levels, recorded by the walk itself (two_level_record.h), as a dict; "
             "with camera_of (a RenderScene of this scene), passing by the primitives its camera rays do not see.")
        .def("occluded", &py_occluded, "origins"_a.noconvert(), "directions"_a.noconvert(), "tmin"_a, "tmax"_a,
             "tmax_of"_a.noconvert().none(), "traversal"_a, "threads"_a, "out"_a.noconvert());
    m.def("build_two_level", &build_two_level, "meshes"_a, "mesh_of"_a.noconvert(), "transforms"_a.noconvert(),
          "config"_a,
          "A TLAS over instances (mesh_of[i] placed by transforms[i], 3×4 object-to-world) of the meshes' trees.");
    m.def("check_placement", &py_check_placement, "tree"_a, "mesh"_a, "index"_a.noconvert(), "transforms"_a.noconvert(),
          "ValueError, naming index[i] and mesh, where transforms[i] would place the tree's current version (mesh "
          "`mesh` of a two-level tree) as build_two_level refuses (outside the coordinate range)");
    m.def("default_tlas_config", &default_tlas_config);
}
