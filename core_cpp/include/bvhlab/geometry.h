// geometry.h — the input primitives (triangles and spheres, one tree, report §5.1), checked once.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>
#include "bvhlab/big_vector.h"
#include "bvhlab/prim_ref.h"

namespace bvhlab {

class Cancellation;

/// Borrowed views of the caller's arrays (zero-copy from numpy): triangles are T×3×3 floats
/// (three world-space vertices each), spheres S×4 floats (centre x, y, z, radius).
struct GeometryView {
    const float* triangles = nullptr;
    std::size_t triangle_count = 0;
    const float* spheres = nullptr;
    std::size_t sphere_count = 0;

    std::size_t primitive_count() const { return triangle_count + sphere_count; }
    Vec3 vertex(std::size_t tri, int corner) const {
        const float* v = triangles + 9 * tri + 3 * corner;
        return {v[0], v[1], v[2]};
    }
    Vec3 sphere_center(std::size_t s) const { return {spheres[4 * s], spheres[4 * s + 1], spheres[4 * s + 2]}; }
    float sphere_radius(std::size_t s) const { return spheres[4 * s + 3]; }
};

/// Throws std::invalid_argument naming the first bad primitive: a NaN or infinite coordinate, a
/// coordinate (or sphere extent) outside ±kMaxCoordinate (coordinate_range.h), a radius that is
/// not a finite number of at least kMinRadius, or more primitives than a reference can index.
/// (A tree's extent is checked where it is made: check_extent, by make_prim_refs and the refit.)
/// Degenerate (zero-area) triangles are valid: they are built into the tree and never hit.
void validate(const GeometryView& geometry);

/// Throws std::invalid_argument when a tree holding `triangle_count` > 0 triangles has a box
/// `box` (of all its primitives) whose largest side is above 0 and below kMinExtent
/// (coordinate_range.h: the triangle test would lose hits).
void check_extent(const Aabb& box, std::size_t triangle_count);

/// The box of primitive `ref` (a triangle's three vertices, a sphere's centre ± radius): the box
/// make_prim_refs gives its reference. The one definition (the saved-tree checks and the tests use it).
Aabb prim_box(const GeometryView& geometry, std::uint32_t ref);

/// What make_prim_refs gathers in its pass over the input besides the references.
struct PrimRefsSummary {
    std::uint64_t fingerprint = 0;  ///< geometry_fingerprint(geometry)
    Aabb box;                       ///< of the references' boxes (empty without primitives)
    Aabb centroids;                 ///< of their centroids, halved twice-centroids (NodeBounds)
};

/// One PrimRef per primitive: triangles first (refs 0..T-1), then spheres (REF_SPHERE_BIT | i),
/// on up to `threads` threads of the shared pool (0: all; the result does not depend on it).
/// Checks the geometry as validate() does, throwing the same errors. `summary`, if set, receives
/// the fingerprint and the bounds, taken in the same pass. `cancel`, if set, is polled on the
/// calling thread before each chunk and while it waits for the others; once it asks to stop, the
/// chunks not yet begun are skipped and the call returns no references (the caller, which made
/// the Cancellation, then stops).
BigVector<PrimRef> make_prim_refs(const GeometryView& geometry, unsigned threads = 1,
                                  PrimRefsSummary* summary = nullptr, Cancellation* cancel = nullptr);

/// A 64-bit fingerprint of the geometry (counts and every coordinate's bits, each primitive's at
/// its place), so that a tree can tell whether it is used with the geometry it was built for (a
/// render of another scene with the same primitive counts would be silently wrong). A change to
/// one primitive always changes it. On up to `threads` threads (0: all); the same value for any.
std::uint64_t geometry_fingerprint(const GeometryView& geometry, unsigned threads = 0);

/// A primitive in the one packed layout of the ray tests (gpu::GpuTriangle, 48 bytes): a
/// triangle's three vertices, or a sphere's centre (v0) and radius (v1.x); `ref` says which.
/// The CPU traversal keeps them in leaf order (Bvh::prims), the tracer its triangles by index.
using PackedPrim = gpu::GpuTriangle;
/// Packing writes every element (pack_prims, or the build's leaves as they are made; the tracer's
/// triangle array): zeroing 48 bytes a primitive first took 1.3% of a Sponza build.
template <>
struct WrittenBeforeRead<PackedPrim> : std::true_type {};

/// geometry_fingerprint of the geometry that `prims` (count of them, in any order) were packed
/// from, read back from the packed words: right where they hold every primitive once and each
/// word as the input has it, i.e. no triangle of zero area (packed as a point) among them. A
/// refit's fingerprint is taken this way when first read (Bvh::fingerprint).
std::uint64_t packed_fingerprint(const PackedPrim* prims, std::size_t count, std::size_t triangle_count,
                                 std::size_t sphere_count);

/// Triangle `i` packed with `material`. A triangle of zero area (its edges' cross product is 0 in
/// float) is stored as three copies of its first vertex, which the watertight test never hits
/// (its edge functions are exactly 0). The one packing of triangles, for the CPU and the GPU.
PackedPrim pack_triangle(const GeometryView& geometry, std::size_t i, std::uint32_t material = 0);

/// Primitive `ref` (a triangle or a sphere) packed for the CPU traversal (material 0).
PackedPrim pack_prim(const GeometryView& geometry, std::uint32_t ref);

/// pack_prim of refs[0 .. count) into out[0 .. count), each input fetched a few references ahead
/// (pack_prims packs in such runs; so does the builder, see BuildShared::prims).
/// `fetched`: the caller has fetched the input already (prefetch_prim), so none is fetched ahead.
void pack_run(const GeometryView& geometry, const std::uint32_t* refs, std::size_t count, PackedPrim* out,
              bool fetched = false);
/// Asks for the input of primitive `ref` to be brought into the caches.
inline void prefetch_prim(const GeometryView& g, std::uint32_t ref) {
    const std::size_t i = ref_index(ref);
    const float* p = is_sphere_ref(ref) ? g.spheres + 4 * i : g.triangles + 9 * i;
    __builtin_prefetch(p), __builtin_prefetch(p + 8);  // 36 bytes may span two lines
}

/// Geometry reordered into the order of `refs` (the tree's leaf order), on up to `threads`
/// threads of the shared pool (0: all; the result does not depend on it).
BigVector<PackedPrim> pack_prims(const GeometryView& geometry, const BigVector<std::uint32_t>& refs,
                                 unsigned threads = 1);

}  // namespace bvhlab
