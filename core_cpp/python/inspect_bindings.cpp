// inspect_bindings.cpp — the bindings for inspecting a tree (issue 35): every node's data as
// numpy arrays, made in C++ for all nodes at once.
#include <utility>
#include <vector>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include "bvhlab/node_data.h"
#include "py_bvh.h"

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

}  // namespace

void bind_inspect(nb::module_& m) {
    nb::class_<PyBvh> bvh = nb::borrow<nb::class_<PyBvh>>(m.attr("Bvh"));
    bvh.def("node_data", &py_node_data, "threads"_a,
            "Every node's data (node_data.h) as a dict of arrays, plus sah_cost and epo_cost.");
}
