// py_bvh.h — what the Python module keeps per tree, shared by the binding files.
#pragma once
#include <optional>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include "bvhlab/bvh.h"
#include "bvhlab/depth_order.h"
#include "bvhlab/wide_bvh.h"

namespace bvhlab::python {

namespace nb = nanobind;
using Triangles = nb::ndarray<const float, nb::shape<-1, 3, 3>, nb::c_contig, nb::device::cpu>;
using Spheres = nb::ndarray<const float, nb::shape<-1, 4>, nb::c_contig, nb::device::cpu>;

inline GeometryView view_of(const Triangles& tris, const std::optional<Spheres>& spheres) {
    GeometryView g;
    g.triangles = tris.data();
    g.triangle_count = tris.shape(0);
    if (spheres) g.spheres = spheres->data(), g.sphere_count = spheres->shape(0);
    return g;
}

/// A Bvh plus the depth order the overlay queries need, computed once on first use.
struct PyBvh {
    Bvh bvh;
    std::optional<DepthOrder> depth_order;
    std::optional<WideBvh> wide_bvh;
    const DepthOrder& order() {
        if (!depth_order) depth_order = make_depth_order(bvh);
        return *depth_order;
    }
    const WideBvh& wide() {  // built on first use, with the GIL held
        if (!wide_bvh) wide_bvh = make_wide(bvh);
        return *wide_bvh;
    }
    void invalidate() { depth_order.reset(), wide_bvh.reset(); }
};

}  // namespace bvhlab::python
