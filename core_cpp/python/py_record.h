// py_record.h — node data (node_data.h) and traversal records (ray_record.h) as the dicts of numpy
// arrays that bvhlab.inspect's NodeData and RayRecord are made from (inspect_bindings.cpp,
// tlas_bindings.cpp).
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include "bvhlab/node_data.h"
#include "bvhlab/ray_record.h"

namespace bvhlab::python {

namespace nb = nanobind;

/// A numpy array that owns `v` (moved, not copied), shaped (len) or (len / width, width).
template <class T>
nb::ndarray<nb::numpy, T> owned_array(std::vector<T>&& v, std::size_t width = 0) {
    auto* held = new std::vector<T>(std::move(v));
    nb::capsule owner(held, [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
    if (width == 0) return nb::ndarray<nb::numpy, T>(held->data(), {held->size()}, owner);
    return nb::ndarray<nb::numpy, T>(held->data(), {held->size() / width, width}, owner);
}

/// Node data (node_data.h, moved out) as the dict NodeData.from_core reads.
inline nb::dict node_data_dict(NodeData&& d) {
    nb::dict out;
    out["lo"] = owned_array(std::move(d.lo), 3), out["hi"] = owned_array(std::move(d.hi), 3);
    out["depth"] = owned_array(std::move(d.depth)), out["parent"] = owned_array(std::move(d.parent));
    out["left"] = owned_array(std::move(d.left)), out["right"] = owned_array(std::move(d.right));
    out["prim_count"] = owned_array(std::move(d.prim_count)), out["area"] = owned_array(std::move(d.area));
    out["sah_term"] = owned_array(std::move(d.sah_term)), out["subtree_sah"] = owned_array(std::move(d.subtree_sah));
    out["sah_share"] = owned_array(std::move(d.sah_share));
    out["child_overlap"] = owned_array(std::move(d.child_overlap)), out["epo"] = owned_array(std::move(d.epo));
    out["sah_cost"] = d.sah_cost, out["epo_cost"] = d.epo_cost, out["surface_area"] = d.surface_area;
    return out;
}

/// `r` (moved out) as a dict: the hit's fields as Bvh.intersect writes them (prim -1, kind 0 on a
/// miss), slot and leaf (-1 on a miss), the steps as arrays; `refs` are the tree's references in
/// leaf order (prim_refs: each tested slot's). A TLAS record's "primitives" are instances: pass
/// null refs and prim_refs are the instances themselves.
inline nb::dict record_dict(TraversalRecord&& r, const std::uint32_t* refs) {
    nb::dict out;
    const bool miss = r.hit.ref == kNoHit;
    out["t"] = r.hit.t, out["u"] = r.hit.u, out["v"] = r.hit.v;
    out["prim"] = miss ? -1 : std::int32_t(r.hit.ref & gpu::REF_INDEX_MASK);
    out["kind"] = miss ? 0 : ((r.hit.ref & gpu::REF_SPHERE_BIT) ? 1 : 0);
    out["hit_slot"] = miss ? -1 : std::int64_t(r.hit.slot);
    out["hit_leaf"] = miss || r.hit_leaf == kNoHit ? -1 : std::int64_t(r.hit_leaf);
    std::vector<std::uint32_t> prim_refs(r.prim_slots.size());
    for (std::size_t j = 0; j < prim_refs.size(); ++j) prim_refs[j] = refs ? refs[r.prim_slots[j]] : r.prim_slots[j];
    out["box_nodes"] = owned_array(std::move(r.box_nodes)), out["box_hit"] = owned_array(std::move(r.box_hit));
    out["prim_slots"] = owned_array(std::move(r.prim_slots)), out["prim_refs"] = owned_array(std::move(prim_refs));
    out["prim_leaf"] = owned_array(std::move(r.prim_leaf));
    out["prim_box_test"] = owned_array(std::move(r.prim_box_test));
    out["prim_closer"] = owned_array(std::move(r.prim_closer));
    out["nodes_visited"] = r.nodes_visited;
    out["wide_nodes"] = owned_array(std::move(r.wide_nodes));
    out["box_wide_step"] = owned_array(std::move(r.box_wide_step));
    return out;
}

}  // namespace bvhlab::python
