// Refit (report §1 names it as future work, after Bikker): moved geometry, same topology.
//
// One pass over the nodes packs each leaf's geometry (the ray tests' copy, Bvh::prims), takes the
// leaf's box from what it just packed and each inner node's from its children once its subtree is
// done, checking coordinates on the way; the fingerprint is taken in its own pass, in input order
// (summing its terms in this pass, in leaf order, took twice as long: 5 against 2.5 ms for 1M
// triangles). No primitive references are made and nothing of the old tree is copied but its
// topology (tinybvh's Refit reads each leaf's vertices the same way). A 1M-triangle refit took
// 89-105 ms when it made references (make_prim_refs), gathered their boxes at random and copied
// the whole tree first; 12 ms for this pass and 2.5 ms for the fingerprint on one core
// (bench/instancing.py).
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "bvhlab/bvh.h"
#include "bvhlab/coordinate_range.h"
#include "bvhlab/simd.h"

namespace bvhlab {
namespace {

/// What the pass gathers besides the boxes: x·0 is 0 for finite x and NaN otherwise, so one sum
/// tells whether any coordinate was NaN or infinite (make_prim_refs' check); the largest
/// |coordinate| for the range check.
struct Checks {
    F4 poison = F4::splat(0.0f), reach = F4::splat(0.0f);
    bool small_radius = false;

    void row(F4 p) { poison = poison + p * F4::splat(0.0f), reach = max(reach, max(p, neg(p))); }
    bool bad() const {
        float lanes_poison[4], lanes_reach[4];
        poison.store(lanes_poison), reach.store(lanes_reach);
        for (int k = 0; k < 3; ++k)
            if (lanes_poison[k] != 0.0f || !(lanes_reach[k] <= kMaxCoordinate)) return true;
        return small_radius;
    }
};

/// Grows lo/hi by the box of a packed primitive as the builder has it (its PrimRef's). A
/// zero-area triangle is packed as one point (pack_triangle): its box comes from the input, so
/// that leaves still contain every primitive's box.
inline void grow_packed(const PackedPrim& p, const GeometryView& g, F4& lo, F4& hi, Checks& checks) {
    const float* rows = &p.v0.x;  // v0, material | v1, ref | v2, 0: load3 leaves lane 3 at 0
    if (p.ref & gpu::REF_SPHERE_BIT) {
        const F4 c = F4::load3(rows), r = F4::splat(p.v1.x) * F4::set3(1, 1, 1);
        checks.row(c), checks.row(r);
        checks.small_radius |= !(p.v1.x >= kMinRadius);
        const F4 a = c - r, b = c + r;
        checks.row(a), checks.row(b);
        lo = min(lo, a), hi = max(hi, b);
        return;
    }
    F4 v0 = F4::load3(rows), v1 = F4::load3(rows + 4), v2 = F4::load3(rows + 8);
    if (p.v0.x == p.v1.x && p.v0.y == p.v1.y && p.v0.z == p.v1.z && p.v0.x == p.v2.x && p.v0.y == p.v2.y &&
        p.v0.z == p.v2.z) {
        const float* t = g.triangles + 9 * std::size_t(ref_index(p.ref));
        // set3, not load3: load3 reads four floats, and past the last vertex of the input that is
        // past the end of its array (the fuzz corpus's ASan run caught it)
        v0 = F4::set3(t[0], t[1], t[2]), v1 = F4::set3(t[3], t[4], t[5]), v2 = F4::set3(t[6], t[7], t[8]);
    }
    checks.row(v0), checks.row(v1), checks.row(v2);
    lo = min(lo, min(v0, min(v1, v2))), hi = max(hi, max(v0, max(v1, v2)));
}

/// One forward pass over the nodes in depth-first order: a leaf packs its primitives (the input
/// fetched a few references ahead: leaf order visits it at random) and takes their box; an inner
/// node is opened on a stack and closed, its box the union of its children's, once the node just
/// written is the last of its subtree. Every node is written whole before the pass moves on.
void refit_pass(const Bvh& old, const GeometryView& g, BvhNode* nodes, PackedPrim* prims, Checks& checks) {
    constexpr std::uint32_t kAhead = 12;
    const std::uint32_t slots = static_cast<std::uint32_t>(old.refs.size());
    const std::uint32_t* refs = old.refs.data();
    for (std::uint32_t k = 0; k < std::min(slots, kAhead); ++k) prefetch_prim(g, refs[k]);
    std::uint32_t open[gpu::MAX_TREE_HEIGHT], depth = 0;
    for (std::uint32_t i = 0, count = old.node_count(); i < count; ++i) {
        BvhNode n = old.nodes[i];
        if (!is_leaf(n)) {
            nodes[i] = n;  // its box once its subtree is done
            open[depth++] = i;
            continue;
        }
        F4 lo = F4::splat(std::numeric_limits<float>::infinity()), hi = neg(lo);
        for (std::uint32_t k = n.index, end = n.index + leaf_count(n); k < end; ++k) {
            if (k + kAhead < slots) prefetch_prim(g, refs[k + kAhead]);
            pack_run(g, refs + k, 1, prims + k, true);
            grow_packed(prims[k], g, lo, hi, checks);
        }
        set_box(n, to_aabb(lo, hi));
        nodes[i] = n;
        // close the inner nodes whose subtrees end here, innermost first
        while (depth > 0 && skip_index(nodes[open[depth - 1]], open[depth - 1]) == i + 1) {
            BvhNode& parent = nodes[open[--depth]];
            Aabb box = node_box(nodes[open[depth] + 1]);
            box.grow(node_box(nodes[parent.index]));
            set_box(parent, box);
        }
    }
}

}  // namespace

Bvh refitted(const Bvh& old, const GeometryView& geometry, unsigned threads) {
    if (geometry.triangle_count != old.triangle_count || geometry.sphere_count != old.sphere_count)
        throw std::invalid_argument("refit needs the same number of triangles and spheres the tree was built with");
    if ((geometry.triangle_count && !geometry.triangles) || (geometry.sphere_count && !geometry.spheres))
        throw std::invalid_argument("primitive count given without data");
    Bvh out;
    out.prims = BigVector<PackedPrim>(old.refs.size());  // both written whole by the pass (WrittenBeforeRead)
    out.nodes = BigVector<BvhNode>(old.nodes.size());
    Checks checks;
    refit_pass(old, geometry, out.nodes.data(), out.prims.data(), checks);
    if (checks.bad()) {
        validate(geometry);  // names the first bad primitive
        throw std::invalid_argument("refit: the geometry has a coordinate out of range");
    }
    out.refs = old.refs;
    out.depths = old.depths;
    out.triangle_count = old.triangle_count, out.sphere_count = old.sphere_count;
    out.config = old.config;
    out.build_ms = old.build_ms;
    out.geometry_fingerprint = geometry_fingerprint(geometry, threads);
    return out;
}

void refit(Bvh& bvh, const GeometryView& geometry) { bvh = refitted(bvh, geometry, 1); }

}  // namespace bvhlab
