// py_boxes.h — the boxes of a tree's nodes by depth as numpy arrays: `Bvh.boxes` (module.cpp) and
// the TLAS's boxes of a two-level tree (`TwoLevel.tlas_boxes`, tlas_bindings.cpp), one definition.
#pragma once
#include <cstdint>
#include <vector>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include "bvhlab/bvh.h"
#include "bvhlab/depth_order.h"

namespace bvhlab::python {

/// Boxes of the nodes (only the leaves if asked) whose depth is in [depth_min, depth_max], by
/// depth (report §3.3.1), in `order` (the tree's depth_order): (lo (K,3), hi (K,3), depth (K,)).
inline nanobind::tuple boxes_by_depth(const Bvh& bvh, const DepthOrder& order, std::uint32_t depth_min,
                                      std::uint32_t depth_max, bool leaves_only) {
    namespace nb = nanobind;
    auto [first, last] = order.range(depth_min, depth_max);
    std::vector<std::uint32_t> picked;
    picked.reserve(last - first);
    for (std::uint32_t j = first; j < last; ++j)
        if (!leaves_only || is_leaf(bvh.nodes[order.nodes[j]])) picked.push_back(order.nodes[j]);
    const std::size_t k = picked.size();
    auto* lo = new float[3 * k];
    auto* hi = new float[3 * k];
    auto* depth = new std::uint8_t[k];
    for (std::size_t j = 0; j < k; ++j) {
        const BvhNode& n = bvh.nodes[picked[j]];
        lo[3 * j] = n.lo.x, lo[3 * j + 1] = n.lo.y, lo[3 * j + 2] = n.lo.z;
        hi[3 * j] = n.hi.x, hi[3 * j + 1] = n.hi.y, hi[3 * j + 2] = n.hi.z;
        depth[j] = bvh.depths[picked[j]];
    }
    auto owned = [](auto* p) { return nb::capsule(p, [](void* q) noexcept { delete[] static_cast<decltype(p)>(q); }); };
    return nb::make_tuple(nb::ndarray<nb::numpy, float, nb::ndim<2>>(lo, {k, 3}, owned(lo)),
                          nb::ndarray<nb::numpy, float, nb::ndim<2>>(hi, {k, 3}, owned(hi)),
                          nb::ndarray<nb::numpy, std::uint8_t, nb::ndim<1>>(depth, {k}, owned(depth)));
}

}  // namespace bvhlab::python
