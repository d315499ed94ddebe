// bvh.h — the built tree: flattened depth-first nodes, leaf-ordered references, per-node depth.
#pragma once
#include <atomic>
#include <cstdint>
#include <type_traits>
#include <vector>
#include "bvhlab/build_config.h"
#include "bvhlab/geometry.h"
#include "gpu_types.h"

namespace bvhlab {

using gpu::BvhNode;
/// Every node is written whole before it is read (SubtreeWriter::open, assemble), so a node array
/// grows without first zeroing the boxes that vec3's initialisers would zero: a two-thread Sponza
/// build zeroed 8.5 MB on one thread before the parts were copied in.
template <>
struct WrittenBeforeRead<BvhNode> : std::true_type {};

/// A tree's geometry fingerprint (geometry_fingerprint), known, or to be taken from the tree's
/// packed primitives when first read (Bvh::fingerprint). Readers on several threads may race to
/// take it: each computes the same value, so the one stored is right either way.
class LazyFingerprint {
public:
    LazyFingerprint() = default;
    // noexcept, so that Bvh's moves are (a std::vector of trees or of parts holding one moves
    // them when it grows, instead of copying them)
    LazyFingerprint(const LazyFingerprint& o) noexcept { *this = o; }
    LazyFingerprint& operator=(const LazyFingerprint& o) noexcept {
        const bool known = o.known_.load(std::memory_order_acquire);
        value_.store(o.value_.load(std::memory_order_relaxed), std::memory_order_relaxed);
        known_.store(known, std::memory_order_release);
        return *this;
    }
    bool known() const { return known_.load(std::memory_order_acquire); }
    std::uint64_t value() const { return value_.load(std::memory_order_relaxed); }  ///< once known()
    void set(std::uint64_t v) const {
        value_.store(v, std::memory_order_relaxed);
        known_.store(true, std::memory_order_release);
    }
    void forget() { known_.store(false, std::memory_order_release); }

private:
    mutable std::atomic<std::uint64_t> value_{0};
    mutable std::atomic<bool> known_{true};
};

/// A bounding volume hierarchy over triangles and spheres.
/// Layout (docs/design.md "Tree layout", report §3.1): nodes in depth-first order, root at 0,
/// first child at i + 1, second child in `index`; leaves reference the contiguous slice
/// refs[index, index + count), the leaves' slices tiling refs (in depth-first order after a build
/// or a refit; an update that rebuilt the upper levels leaves its cut subtrees' slices in place).
/// Depth of the root is 0; height is the largest leaf depth + 1 (an empty tree has height 0).
struct Bvh {
    BigVector<BvhNode> nodes;
    BigVector<std::uint32_t> refs;   ///< primitive references in leaf order
    BigVector<std::uint8_t> depths;  ///< depth of each node
    BigVector<PackedPrim> prims;     ///< geometry in leaf order, for the CPU traversal
    std::uint32_t triangle_count = 0, sphere_count = 0;
    BuildConfig config;   ///< what it was built with (progress callback dropped)
    double build_ms = 0;  ///< wall time of the tree build (refs in → nodes out)

    /// geometry_fingerprint of the geometry built over (or last refitted to). A refit leaves it to
    /// be taken from `prims` when first read (set_fingerprint_from_prims): an update's pass over
    /// the input that nothing may read (issue 34).
    std::uint64_t fingerprint() const {
        if (!fingerprint_.known())
            fingerprint_.set(packed_fingerprint(prims.data(), prims.size(), triangle_count, sphere_count));
        return fingerprint_.value();
    }
    void set_fingerprint(std::uint64_t value) { fingerprint_.set(value); }
    /// Only where `prims` holds every primitive once, with its input's exact words (a refit's,
    /// where no triangle was packed as a point: packed_fingerprint).
    void set_fingerprint_from_prims() { fingerprint_.forget(); }

    bool empty() const { return nodes.empty(); }
    std::uint32_t node_count() const { return static_cast<std::uint32_t>(nodes.size()); }

private:
    LazyFingerprint fingerprint_;
};
static_assert(std::is_nothrow_move_constructible_v<Bvh> && std::is_nothrow_move_assignable_v<Bvh>);

inline bool is_leaf(const BvhNode& n) { return (n.info & gpu::NODE_INTERNAL_BIT) == 0; }
inline std::uint32_t leaf_count(const BvhNode& n) { return n.info; }
/// Next node in depth-first order after node i's subtree.
inline std::uint32_t skip_index(const BvhNode& n, std::uint32_t i) {
    return is_leaf(n) ? i + 1 : (n.info & ~gpu::NODE_INTERNAL_BIT);
}
inline Aabb node_box(const BvhNode& n) { return {{n.lo.x, n.lo.y, n.lo.z}, {n.hi.x, n.hi.y, n.hi.z}}; }
inline void set_box(BvhNode& n, const Aabb& b) {
    n.lo = {b.lo.x, b.lo.y, b.lo.z};
    n.hi = {b.hi.x, b.hi.y, b.hi.z};
}

/// Validates the geometry and the config, then builds (see build/build_bvh.cpp).
/// Throws std::invalid_argument on bad input, BuildCancelled when the progress callback says stop.
Bvh build_bvh(const GeometryView& geometry, const BuildConfig& config = {});

/// The same builder over boxes instead of primitives (the TLAS over instances' world boxes,
/// tlas.h): the leaves' references are box indices 0..count-1, no geometry is packed (prims stays
/// empty) and the counts of triangles and spheres are 0. Boxes must be non-empty and finite.
Bvh build_bvh_over_boxes(const Aabb* boxes, std::size_t count, const BuildConfig& config = {});

/// Recomputes every box bottom-up for moved geometry with the same primitive counts, keeping the
/// topology (report §1: the refitting it names as future work; Bikker). O(nodes). Throws
/// std::invalid_argument as build_bvh does for bad geometry, and leaves `bvh` as it was.
void refit(Bvh& bvh, const GeometryView& geometry);

/// The refit of `old` as a new tree, `old` untouched (readers on other threads may keep using
/// it): only its topology is copied; boxes, leaf geometry and fingerprint are made from
/// `geometry` (the fingerprint on up to `threads` threads of the pool, 0: all).
Bvh refitted(const Bvh& old, const GeometryView& geometry, unsigned threads = 1);

/// std::invalid_argument unless `geometry` has the primitive counts `old` was built over (and data
/// for them): what a refit and the updates that keep a tree's primitives require.
void check_same_primitives(const Bvh& old, const GeometryView& geometry);

/// Thrown when a build is cancelled through its progress callback.
struct BuildCancelled : std::exception {
    const char* what() const noexcept override { return "build cancelled"; }
};

}  // namespace bvhlab
