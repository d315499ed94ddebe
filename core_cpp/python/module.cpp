// The nanobind module `bvhlab._core`: thin bindings; checks of Python-side types live in
// python/bvhlab (clear messages), checks of values in the C++ core (std::invalid_argument →
// ValueError). The GIL is released for builds and traversal.
#include <memory>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/function.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/vector.h>

#include "bvhlab/bvh.h"
#include "bvhlab/cancel.h"
#include "bvhlab/coordinate_range.h"
#include "bvhlab/depth_order.h"
#include "bvhlab/render_settings.h"
#include "bvhlab/split.h"
#include "bvhlab/stats.h"
#include "bvhlab/transform.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"
#include "py_boxes.h"
#include "py_bvh.h"
#include "py_cancel.h"
#include "py_occluded.h"

namespace nb = nanobind;
using namespace nb::literals;
using namespace bvhlab;
using namespace bvhlab::python;

namespace {

using Vectors = nb::ndarray<const float, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
template <class T>
using Out1D = nb::ndarray<T, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

nb::dict stats_dict(const Bvh& bvh) {
    BvhStats s = compute_stats(bvh);
    nb::dict d;
    d["primitives"] = s.primitives, d["triangles"] = s.triangles, d["spheres"] = s.spheres;
    d["references"] = s.references;
    d["nodes"] = s.nodes, d["leaves"] = s.leaves, d["height"] = s.height;
    d["sah_cost"] = s.sah_cost, d["build_ms"] = s.build_ms;
    d["avg_leaf_size"] = s.avg_leaf_size, d["max_leaf_size"] = s.max_leaf_size;
    d["nodes_per_depth"] = s.nodes_per_depth, d["leaves_per_depth"] = s.leaves_per_depth;
    d["leaf_size_histogram"] = s.leaf_size_histogram;
    d["memory_bytes"] = s.memory_bytes;
    d["method"] = to_string(bvh.config.method), d["axis"] = to_string(bvh.config.axis);
    // bins and bin_bounds only where the method bins (None: a median tree of "12 bins" used none)
    const bool binned = method_info(bvh.config.method).binned;
    d["bins"] = binned ? nb::cast(bvh.config.bins) : nb::none();
    d["max_leaf_size_config"] = bvh.config.max_leaf_size;
    d["bin_bounds"] = binned ? nb::cast(to_string(bvh.config.bin_bounds)) : nb::none();
    d["sah_block"] = bvh.config.sah_block;
    return d;
}

PyBvh* build(const Triangles& tris, const std::optional<Spheres>& spheres, const BuildConfig& config,
             std::optional<nb::callable> progress) {
    BuildConfig cfg = config;  // the caller's stays as it was (no callback stored in it)
    // Always a check, with or without a callable: Ctrl-C stops the build (KeyboardInterrupt).
    PyStopCheck stop(progress ? nb::object(*progress) : nb::none());
    cfg.progress = [&stop](double done) { return !stop(done); };
    GeometryView g = view_of(tris, spheres);
    Bvh bvh;
    try {
        const LongRelease release;
        bvh = build_bvh(g, cfg);
    } catch (const BuildCancelled&) {
        stop.rethrow();  // what the callable (or Ctrl-C) raised, as itself
        throw;
    }
    return new PyBvh(std::move(bvh));
}

void py_intersect(const PyBvh& self, const Vectors& origins, const Vectors& dirs, float tmin, float tmax,
                  const std::string& traversal, std::uint32_t threads, Out1D<float> t, Out1D<std::int32_t> prim,
                  Out1D<std::uint8_t> kind, Out1D<float> u, Out1D<float> v,
                  std::optional<Out1D<std::uint32_t>> visited) {
    const std::size_t n = origins.shape(0);
    if (dirs.shape(0) != n) throw std::invalid_argument("origins and directions differ in length");
    for (std::size_t len :
         {t.shape(0), prim.shape(0), kind.shape(0), u.shape(0), v.shape(0), visited ? visited->shape(0) : n})
        if (len != n) throw std::invalid_argument("output arrays must have one entry per ray");
    const Traversal mode = parse_traversal(traversal);  // names parsed in one place (render_settings.h)
    RayBatch rays{origins.data(), dirs.data(), n, tmin, tmax};
    // no counts asked: the wide batch may trace camera rays as packets (design.md)
    HitBatch hits{t.data(), prim.data(), kind.data(), u.data(), v.data(), visited ? visited->data() : nullptr};
    TreePtr tree = self.current();  // this version stays alive (and unchanged) until the rays are done
    require_geometry(tree->bvh, "intersect");
    PyStopCheck stop;  // Ctrl-C stops a long batch
    Cancellation cancel([&stop] { return stop(0.0); });
    try {
        const LongRelease release;
        const WideBvh* wide = mode == Traversal::Wide ? &tree->wide() : nullptr;
        intersect_batch(tree->bvh, rays, hits, mode, threads, wide, &cancel);
    } catch (const Cancelled&) {
        stop.rethrow();
        throw;
    }
}

void py_occluded(const PyBvh& self, const Vectors& origins, const Vectors& dirs, float tmin, float tmax,
                 const std::optional<RayFloats>& tmax_of, const std::string& traversal, std::uint32_t threads,
                 Occluded out) {
    const RayBatch rays = occluded_rays(origins, dirs, tmin, tmax, tmax_of, out);
    const Traversal mode = parse_traversal(traversal);
    TreePtr tree = self.current();  // this version stays alive (and unchanged) until the rays are done
    require_geometry(tree->bvh, "occluded");
    run_released([&](Cancellation* cancel) {
        const WideBvh* wide = mode == Traversal::Wide ? &tree->wide() : nullptr;
        occluded_batch(tree->bvh, rays, out.data(), mode, threads, wide, cancel);
    });
}

/// Boxes of the nodes whose depth is in [depth_min, depth_max] (py_boxes.h), read from one
/// version of the tree.
nb::tuple py_boxes(const PyBvh& self, std::uint32_t depth_min, std::uint32_t depth_max, bool leaves_only) {
    TreePtr tree = self.current();
    return boxes_by_depth(tree->bvh, tree->order(), depth_min, depth_max, leaves_only);
}

void py_refit(PyBvh& self, const Triangles& tris, const std::optional<Spheres>& spheres) {
    require_geometry(self.current()->bvh, "refit");
    GeometryView g = view_of(tris, spheres);
    const LongRelease release;
    // the topology stays, and with it the costs its nodes had when built (update.h); an SBVH is
    // rebuilt instead (refitted), a new topology whose costs as built are its own (null: taken
    // from it when first asked), not the old tree's, which an update would refuse
    self.replace([&](const TreeVersion& old) {
        const bool rebuilt = old.bvh.config.method == SplitMethod::Sbvh;
        return std::pair{refitted(old.bvh, g, old.bvh.config.threads), rebuilt ? CostsPtr() : old.built_costs()};
    });
}

}  // namespace

void bind_render(nb::module_& m);        // render_bindings.cpp
void bind_build_config(nb::module_& m);  // build_config_bindings.cpp
void bind_inspect(nb::module_& m);       // inspect_bindings.cpp (after bind_bvh: it adds to Bvh)
void bind_tlas(nb::module_& m);          // tlas_bindings.cpp
void bind_update(nb::module_& m);        // update_bindings.cpp
void bind_optimize(nb::module_& m);      // optimize_bindings.cpp

namespace {

void bind_bvh(nb::module_& m) {
    nb::class_<PyBvh>(m, "Bvh")
        .def("stats", [](const PyBvh& b) { return stats_dict(b.current()->bvh); })
        .def_prop_ro("node_count", [](const PyBvh& b) { return b.current()->bvh.nodes.size(); })
        .def_prop_ro(
            "primitive_counts",
            [](const PyBvh& b) {
                TreePtr t = b.current();
                return nb::make_tuple(t->bvh.triangle_count, t->bvh.sphere_count);
            },
            "(triangles, spheres) of one version, without the stats' pass over the nodes")
        .def_prop_ro("build_ms", [](const PyBvh& b) { return b.current()->bvh.build_ms; })
        .def_prop_ro("revision", [](const PyBvh& b) { return b.current()->revision; })
        .def(
            "fork", [](const PyBvh& b) { return new PyBvh(b.current()); }, nb::rv_policy::take_ownership,
            "a new tree at this one's current version (shared, not copied): updates of either leave the other")
        .def(
            "restore",
            [](PyBvh& b, const PyBvh& earlier) {
                TreePtr tree = earlier.current();
                const LongRelease release;
                b.replace([&](const TreeVersion&) { return std::pair{Bvh(tree->bvh), tree->built_costs()}; });
            },
            "earlier"_a,
            "publishes a copy of `earlier`'s current version (a fork taken before a change) as a new revision: a "
            "change undone without reusing a revision number that caches may have seen")
        .def_prop_ro("geometry_fingerprint", [](const PyBvh& b) { return b.current()->bvh.fingerprint(); })
        .def("nodes_bytes",
             [](const PyBvh& b) {
                 TreePtr t = b.current();
                 return array_owned_by(t, reinterpret_cast<const std::uint8_t*>(t->bvh.nodes.data()),
                                       {t->bvh.nodes.size(), sizeof(BvhNode)});
             })
        .def("refs",
             [](const PyBvh& b) {
                 TreePtr t = b.current();
                 return array_owned_by(t, t->bvh.refs.data(), {t->bvh.refs.size()});
             })
        .def(
            "file_parts",
            [](const PyBvh& b) {
                TreePtr t = b.current();           // one version: a refit or update meanwhile cannot mix two
                require_geometry(t->bvh, "save");  // load_bvh makes the geometry again from a scene
                nb::dict d;
                d["nodes"] = array_owned_by(t, reinterpret_cast<const std::uint8_t*>(t->bvh.nodes.data()),
                                            {t->bvh.nodes.size(), sizeof(BvhNode)});
                d["refs"] = array_owned_by(t, t->bvh.refs.data(), {t->bvh.refs.size()});
                d["geometry_fingerprint"] = t->bvh.fingerprint();
                d["triangles"] = t->bvh.triangle_count, d["spheres"] = t->bvh.sphere_count;
                d["build_ms"] = t->bvh.build_ms, d["revision"] = t->revision;
                return d;
            },
            "What a tree file holds (nodes, refs, fingerprint, counts, build_ms), all of one version")
        .def("depths",
             [](const PyBvh& b) {
                 TreePtr t = b.current();
                 return array_owned_by(t, t->bvh.depths.data(), {t->bvh.depths.size()});
             })
        .def("boxes", &py_boxes, "depth_min"_a, "depth_max"_a, "leaves_only"_a)
        .def(
            "depth_order",
            [](const PyBvh& b) {
                TreePtr t = b.current();
                const DepthOrder& o = t->order();
                return nb::make_tuple(array_owned_by(t, o.nodes.data(), {o.nodes.size()}),
                                      array_owned_by(t, o.offset.data(), {o.offset.size()}));
            },
            "(nodes, offset): node indices by depth; the nodes of depth d are nodes[offset[d]:offset[d + 1]]")
        .def(
            "depth_range",
            [](const PyBvh& b, std::uint32_t depth_min, std::uint32_t depth_max) {
                return b.current()->order().range(depth_min, depth_max);
            },
            "depth_min"_a, "depth_max"_a, "[first, last) in depth_order()'s nodes of the depths depth_min..depth_max")
        .def("intersect", &py_intersect, "origins"_a.noconvert(), "directions"_a.noconvert(), "tmin"_a, "tmax"_a,
             "traversal"_a, "threads"_a, "t"_a.noconvert(), "prim"_a.noconvert(), "kind"_a.noconvert(),
             "u"_a.noconvert(), "v"_a.noconvert(), "visited"_a.noconvert().none())
        .def("occluded", &py_occluded, "origins"_a.noconvert(), "directions"_a.noconvert(), "tmin"_a, "tmax"_a,
             "tmax_of"_a.noconvert().none(), "traversal"_a, "threads"_a, "out"_a.noconvert())
        .def("refit", &py_refit, "triangles"_a.noconvert(), "spheres"_a.noconvert().none());
}

void bind_functions(nb::module_& m) {  // geometry checks and the build
    m.def(
        "geometry_fingerprint",
        [](const Triangles& tris, const std::optional<Spheres>& spheres) {
            GeometryView g = view_of(tris, spheres);
            const LongRelease release;
            return geometry_fingerprint(g);
        },
        "triangles"_a.noconvert(), "spheres"_a.noconvert().none());
    m.def(
        "validate_geometry",
        [](const Triangles& tris, const std::optional<Spheres>& spheres) {
            GeometryView g = view_of(tris, spheres);
            const LongRelease release;
            validate(g);
        },
        "triangles"_a.noconvert(), "spheres"_a.noconvert().none(),
        "Raises ValueError naming the first primitive that is not finite or lies outside MAX_COORDINATE.");
    m.def("build", &build, "triangles"_a.noconvert(), "spheres"_a.noconvert().none(), "config"_a, "progress"_a.none());
}

void bind_build_names(nb::module_& m) {
    // The build's names and defaults, one definition (build_config.h, split_methods.cpp): Python's
    // build() and the add-on's properties read these.
    const BuildConfig defaults;
    nb::list methods, binned, axes, bin_bounds;
    for (std::string_view name : split_method_names()) methods.append(std::string(name));
    for (const SplitMethodInfo& info : split_methods())
        if (info.binned) binned.append(std::string(info.name));
    for (std::string_view name : axis_policy_names()) axes.append(std::string(name));
    for (std::string_view name : bin_bounds_names()) bin_bounds.append(std::string(name));
    m.attr("SPLIT_METHODS") = nb::tuple(methods);
    m.attr("BINNED_METHODS") = nb::tuple(binned);
    m.attr("AXIS_POLICIES") = nb::tuple(axes);
    m.attr("BIN_BOUNDS") = nb::tuple(bin_bounds);
    m.attr("DEFAULT_METHOD") = to_string(defaults.method);
    m.attr("DEFAULT_AXIS") = to_string(defaults.axis);
    m.attr("DEFAULT_BINS") = defaults.bins;
    m.attr("DEFAULT_BIN_BOUNDS") = to_string(defaults.bin_bounds);
    m.attr("DEFAULT_MAX_LEAF_SIZE") = defaults.max_leaf_size;
    m.attr("DEFAULT_SAH_BLOCK") = defaults.sah_block;
    m.attr("MAX_TREE_HEIGHT") = gpu::MAX_TREE_HEIGHT;
    m.attr("MAX_COORDINATE") = kMaxCoordinate;  // coordinate_range.h
    m.attr("MIN_DIRECTION") = kMinDirection;
    m.attr("MAX_DIRECTION") = kMaxDirection;
    m.attr("MIN_RADIUS") = kMinRadius;
    m.attr("MAX_TRANSFORM_ENTRY") = kMaxTransformEntry;  // transform.h
    m.attr("NODE_INTERNAL_BIT") = gpu::NODE_INTERNAL_BIT;
    m.attr("REF_SPHERE_BIT") = gpu::REF_SPHERE_BIT;
}

}  // namespace

NB_MODULE(_core, m) {
    m.doc() = "bvhlab C++ core: BVH construction, stats, CPU traversal and the renderers";
    forget_long_calls_in_forked_children();
    m.def("_finish_long_calls", &finish_long_calls, "seconds"_a,
          "At exit (bvhlab's atexit handler): every long call from Python on another thread parks at its "
          "next look at Ctrl-C or on its way back, without the GIL, until the process ends; those in "
          "progress are waited for up to `seconds`. True when every one has parked.");
    nb::exception<BuildCancelled>(m, "BuildCancelled");
    bind_render(m);
    bind_bvh(m);
    bind_inspect(m);
    bind_build_config(m);
    bind_tlas(m);
    bind_update(m);
    bind_optimize(m);
    bind_functions(m);
    bind_build_names(m);
}
