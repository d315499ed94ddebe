// Refit (report §1 names it as future work, after Bikker): moved geometry, same topology.
#include <stdexcept>

#include "bvhlab/bvh.h"

namespace bvhlab {

void refit(Bvh& bvh, const GeometryView& geometry) {
    if (geometry.triangle_count != bvh.triangle_count || geometry.sphere_count != bvh.sphere_count)
        throw std::invalid_argument("refit needs the same number of triangles and spheres the tree was built with");
    PrimRefsSummary summary;
    BigVector<PrimRef> prim_refs = make_prim_refs(geometry, 1, &summary);
    // make_prim_refs puts triangles first, then spheres
    auto input_slot = [&](std::uint32_t ref) { return ref_index(ref) + (is_sphere_ref(ref) ? bvh.triangle_count : 0); };
    // Children come after their parent in depth-first order, so one backward pass suffices.
    for (std::size_t i = bvh.nodes.size(); i-- > 0;) {
        BvhNode& n = bvh.nodes[i];
        Aabb box;
        if (is_leaf(n)) {
            for (std::uint32_t k = 0; k < leaf_count(n); ++k)
                box.grow(prim_refs[input_slot(bvh.refs[n.index + k])].box());
        } else {
            box = node_box(bvh.nodes[i + 1]);
            box.grow(node_box(bvh.nodes[n.index]));
        }
        set_box(n, box);
    }
    bvh.prims = pack_prims(geometry, bvh.refs);
    bvh.geometry_fingerprint = summary.fingerprint;
}

}  // namespace bvhlab
