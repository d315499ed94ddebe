// Refit (report §1 names it as future work, after Bikker): moved geometry, same topology.
//
// One pass over the nodes, backwards, packs each leaf's geometry (the ray tests' copy, Bvh::prims),
// takes the leaf's box from the vertices it read and each inner node's from its two children,
// checking coordinates on the way; the fingerprint is taken from the packed copy when first read
// (Bvh::fingerprint; in its own pass over the input, in input order, where a triangle was packed
// as a point)
// (summing its terms in this pass, in leaf order, took twice as long: 5 against 2.5 ms for 1M
// triangles). No primitive references are made and nothing of the old tree is copied but its
// topology (tinybvh's Refit reads each leaf's vertices the same way). A 1M-triangle refit took
// 89-105 ms when it made references (make_prim_refs), gathered their boxes at random and copied
// the whole tree first; 12 ms for a forward pass (a stack of open inner nodes, each written twice,
// a packing call a primitive and its box read back) and 2.5 ms for the fingerprint on one core
// (bench/instancing.py); bench/updates.py has the figures of this pass.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "bvhlab/bvh.h"
#include "bvhlab/coordinate_range.h"
#include "bvhlab/simd.h"
#include "../query/pack_triangle.h"

namespace bvhlab {
namespace {

/// What the pass gathers besides the boxes: x·0 is 0 for finite x and NaN otherwise, so one sum
/// tells whether any coordinate was NaN or infinite (make_prim_refs' check); the largest
/// |coordinate| is the root box's (a sphere's centre and radius are checked on their own).
struct Checks {
    F4 poison = F4::splat(0.0f), reach = F4::splat(0.0f);
    bool small_radius = false;
    bool point = false;  ///< a triangle of zero area was packed as a point (its words not kept)

    void row(F4 p) { poison = poison + p * F4::splat(0.0f), reach = max(reach, max(p, neg(p))); }
    /// One triangle: its vertices' sum is finite when they are (in range, they cannot overflow).
    void triangle(F4 a, F4 b, F4 c) { poison = poison + (a + b + c) * F4::splat(0.0f); }
    bool bad(const Aabb& root) const {
        float lanes_poison[4], lanes_reach[4];
        poison.store(lanes_poison), reach.store(lanes_reach);
        for (int k = 0; k < 3; ++k)
            if (lanes_poison[k] != 0.0f || !(lanes_reach[k] <= kMaxCoordinate)) return true;
        return small_radius || !in_coordinate_range(root.lo) || !in_coordinate_range(root.hi);
    }
};

/// Grows lo/hi by sphere `ref`'s box (its PrimRef's) and packs it.
inline void refit_sphere(const GeometryView& g, std::uint32_t ref, PackedPrim* out, F4& lo, F4& hi, Checks& checks) {
    *out = pack_prim(g, ref);
    const F4 c = F4::load3(&out->v0.x), r = F4::splat(out->v1.x) * F4::set3(1, 1, 1);
    checks.row(c), checks.row(r);
    checks.small_radius |= !(out->v1.x >= kMinRadius);
    const F4 a = c - r, b = c + r;
    checks.row(a), checks.row(b);
    lo = min(lo, a), hi = max(hi, b);
}

/// Node `n` (as it was) with the box [lo, hi]: lane 3 of each row keeps its index and info words.
inline void store_node(BvhNode* dst, const BvhNode& n, F4 lo, F4 hi) {
    const F4 xyz = less(F4::splat(0.0f), F4::set3(1, 1, 1));  // lanes 0-2 set
    select(xyz, lo, F4::load(&n.lo.x)).store(&dst->lo.x);
    select(xyz, hi, F4::load(&n.hi.x)).store(&dst->hi.x);
}

/// Leaf `n` (as it was) with the box [lo, hi] and its run of slots starting at `first`. The lo
/// row's lane 3 (the index) is set in a register: setting it in a copy of the node and loading
/// the row back made every leaf wait on a failed store-to-load forwarding (a 4-byte store under
/// a 16-byte load; perf put a fifth of the refit's samples there).
inline void store_leaf(BvhNode* dst, const BvhNode& n, std::uint32_t first, F4 lo, F4 hi) {
    const F4 xyz = less(F4::splat(0.0f), F4::set3(1, 1, 1));  // lanes 0-2 set
#ifdef BVHLAB_SSE
    const __m128 index = _mm_castsi128_ps(_mm_slli_si128(_mm_cvtsi32_si128(int(first)), 12));  // lane 3
    F4{_mm_or_ps(_mm_and_ps(xyz.v, lo.v), index)}.store(&dst->lo.x);
#else
    float row[4];
    lo.store(row);
    std::memcpy(&row[3], &first, 4);
    F4::load(row).store(&dst->lo.x);
#endif
    select(xyz, hi, F4::load(&n.hi.x)).store(&dst->hi.x);
}

/// One pass over the nodes in reverse depth-first order, so that both children of a node (at
/// i + 1 and at its index, both after it) are done before it: an inner node's box is the union
/// of theirs (two loads and a min and a max a side), a leaf packs its primitives (the tree's
/// geometry copy, Bvh::prims, written backwards; the input fetched kAhead references ahead, as
/// leaf order visits it at random) and takes their box from the vertices it read. Every node
/// and primitive is written once, with no stack (tinybvh's Refit walks its nodes backwards too).
/// The leaves' slots are laid down again in depth-first order (`refs` written leaf by leaf, each
/// leaf's index moved to its run): a tree whose upper levels an update rebuilt keeps its cut
/// subtrees' runs where they were (rebuild_top.h), and this puts them back in order at no cost
/// beyond writing the references (the old tree's are read either way).
/// A zero-area triangle is packed as one point (pack_triangle) but boxed from the input, so that
/// leaves still contain every primitive's box (its PrimRef's).
void refit_pass(const Bvh& old, const GeometryView& g, BvhNode* nodes, std::uint32_t* out_refs, PackedPrim* prims,
                Checks& checks) {
    constexpr std::uint32_t kAhead = 16;
    const std::uint32_t* refs = old.refs.data();
    const F4 empty = F4::splat(std::numeric_limits<float>::infinity());
    std::uint32_t end = static_cast<std::uint32_t>(old.refs.size());  // the leaves after node i take [end, slots)
    // the next leaves' references, kAhead slots ahead in the order the pass reads them
    std::uint32_t ahead_node = old.node_count(), ahead_slot = 0, ahead_left = 0;
    auto prefetch_next = [&] {
        while (ahead_left == 0 && ahead_node > 0) {
            const BvhNode& m = old.nodes[--ahead_node];
            if (is_leaf(m)) ahead_slot = m.index + leaf_count(m), ahead_left = leaf_count(m);
        }
        if (ahead_left == 0) return;
        prefetch_prim(g, refs[--ahead_slot]), --ahead_left;
    };
    for (std::uint32_t k = 0; k < kAhead; ++k) prefetch_next();
    // the box of node i + 1 (the first child of an inner node i), the last iteration's, kept in
    // registers: loaded back from the node just stored, each inner node waited on that store
    F4 next_lo = empty, next_hi = neg(empty);
    for (std::uint32_t i = old.node_count(); i-- > 0;) {
        const BvhNode& n = old.nodes[i];
        if (!is_leaf(n)) {
            const BvhNode& b = nodes[n.index];
            next_lo = min(next_lo, F4::load(&b.lo.x)), next_hi = max(next_hi, F4::load(&b.hi.x));
            store_node(nodes + i, n, next_lo, next_hi);
            continue;
        }
        F4 lo = empty, hi = neg(empty);
        end -= leaf_count(n);
        for (std::uint32_t k = leaf_count(n); k-- > 0;) {
            prefetch_next();
            const std::uint32_t ref = refs[n.index + k], slot = end + k;
            out_refs[slot] = ref;
            if (is_sphere_ref(ref)) {
                refit_sphere(g, ref, prims + slot, lo, hi, checks);
                continue;
            }
            F4 a, b, c;
            checks.point |= pack_triangle_rows(prims + slot, g.triangles + 9 * std::size_t(ref), ref, 0, a, b, c);
            checks.triangle(a, b, c);
            lo = min(lo, min(a, min(b, c))), hi = max(hi, max(a, max(b, c)));
        }
        store_leaf(nodes + i, n, end, lo, hi);
        next_lo = lo, next_hi = hi;
    }
}

}  // namespace

void check_same_primitives(const Bvh& old, const GeometryView& geometry) {
    if (geometry.triangle_count != old.triangle_count || geometry.sphere_count != old.sphere_count)
        throw std::invalid_argument(
            "a refit or update keeps the tree's primitives: it was built over " + std::to_string(old.triangle_count) +
            " triangles and " + std::to_string(old.sphere_count) + " spheres, got " +
            std::to_string(geometry.triangle_count) + " and " + std::to_string(geometry.sphere_count) +
            " (for another count, build a new tree, or update with policy rebuild)");
    if ((geometry.triangle_count && !geometry.triangles) || (geometry.sphere_count && !geometry.spheres))
        throw std::invalid_argument("primitive count given without data");
}

Bvh refitted(const Bvh& old, const GeometryView& geometry, unsigned threads) {
    check_same_primitives(old, geometry);
    // An SBVH's leaf boxes hold clipped parts of its primitives (sbvh/chop.h): a refit would have
    // to clip again at planes the tree does not keep, so it is rebuilt with its settings instead.
    if (old.config.method == SplitMethod::Sbvh) return build_bvh(geometry, old.config);
    Bvh out;
    out.prims = BigVector<PackedPrim>(old.refs.size());  // all three written whole by the pass
    out.nodes = BigVector<BvhNode>(old.nodes.size());
    out.refs = BigVector<std::uint32_t>(old.refs.size());
    Checks checks;
    refit_pass(old, geometry, out.nodes.data(), out.refs.data(), out.prims.data(), checks);
    const Aabb root = out.nodes.empty() ? Aabb{Vec3{0.0f}, Vec3{0.0f}} : node_box(out.nodes[0]);
    if (checks.bad(root)) {
        validate(geometry);  // names the first bad primitive
        throw std::invalid_argument("refit: the geometry has a coordinate out of range");
    }
    check_extent(root, geometry.triangle_count);
    out.depths = old.depths;
    out.triangle_count = old.triangle_count, out.sphere_count = old.sphere_count;
    out.config = old.config;
    out.build_ms = old.build_ms;
    // the fingerprint when first read, from the packed words (each the input's, unless a triangle
    // was packed as a point): a pass over the input, a sixth of the refit's time, otherwise
    if (checks.point) out.set_fingerprint(geometry_fingerprint(geometry, threads));
    else out.set_fingerprint_from_prims();
    return out;
}

void refit(Bvh& bvh, const GeometryView& geometry) { bvh = refitted(bvh, geometry, 1); }

}  // namespace bvhlab
