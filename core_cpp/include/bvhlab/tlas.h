// tlas.h — two-level trees (issue 34): a bottom-level tree (BLAS, the ordinary Bvh) per mesh,
// shared by every instance of it, and a top-level tree (TLAS) over the instances, as Embree,
// OptiX and tinybvh (BVH::BuildTLAS) arrange instanced scenes. A mesh instanced N times costs one
// BLAS and O(N) bytes.
#pragma once
#include <cstdint>
#include <vector>

#include "bvhlab/big_vector.h"
#include "bvhlab/bvh.h"
#include "bvhlab/transform.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"

namespace bvhlab {

/// One placement of a mesh: which BLAS, where (object-to-world and its inverse), and the world
/// box the TLAS is built over (the union of the BLAS's top eight boxes moved into the world,
/// transform_box: tighter than its moved root box where the instance is rotated).
struct Instance {
    std::uint32_t blas = 0;
    Transform object_to_world, world_to_object;
    Aabb world_box;        ///< empty for an instance of an empty BLAS (never in the TLAS)
    bool identity = true;  ///< object space is world space: rays are not moved (the one-mesh scene)
};

/// An instance as the two-level walks reach it from a TLAS leaf (Tlas::leaf_instances): what
/// moving a ray into its space and naming the hit need, on one cache line, in the order of the
/// TLAS's leaves. Reached through the leaf's node, its ref and then the Instance, a leaf cost three
/// dependent loads, which missed the caches where instances are many (10,000 instances of a
/// 480-triangle knot: 72% of the leaf code's samples on two of them, over a quarter of a shadow ray's
/// time).
struct alignas(64) LeafInstance {
    ObjectColumns to_object;  ///< world to object space (transform.h), by columns
    std::uint32_t blas = 0;
    std::uint32_t instance = 0;  ///< its index in Tlas::instances
    std::uint32_t leaf = 0;      ///< the binary TLAS leaf that holds it (tree.nodes; the inspector's name)
    bool identity = true;        ///< Instance::identity
    bool last = true;            ///< the last instance of its leaf
};
static_assert(sizeof(LeafInstance) == 64);
template <>
struct WrittenBeforeRead<LeafInstance> : std::true_type {};  // build_tlas writes each whole

/// A BLAS as the two-level queries see it: the tree and, for Traversal::Wide, its 8-wide copy.
/// Borrowed: the caller keeps both alive while the TwoLevel that refers to them is used.
struct BlasView {
    const Bvh* bvh = nullptr;
    const WideBvh* wide = nullptr;
};

/// The flat queries of one BLAS, in its object space: `mode` picks the walk (its wide copy for
/// Traversal::Wide).
inline Hit intersect_blas(const BlasView& blas, const Ray& ray, Traversal mode, std::uint32_t* visited) {
    return mode == Traversal::Wide ? intersect_wide(*blas.wide, *blas.bvh, ray, visited)
                                   : intersect(*blas.bvh, ray, mode, visited);
}
inline bool occluded_blas(const BlasView& blas, const Ray& ray, Traversal mode) {
    return mode == Traversal::Wide ? occluded_wide(*blas.wide, ray) : occluded(*blas.bvh, ray, mode);
}

/// The TLAS: a Bvh whose leaves' references are instance indices (no geometry packed), built with
/// the builder of every tree over the instances' world boxes (build_bvh_over_boxes), and its
/// 8-wide copy (make_wide_tlas), which Traversal::Wide walks: a ray visits a wide node where the
/// binary walk tested two boxes at each of several levels (design.md, "The two-level walk's cost").
struct Tlas {
    Bvh tree;
    WideBvh wide;
    /// tree.refs' instances, one a ref in their order (a leaf child of `wide` is kLeafChild | its
    /// leaf's first position here): what the walks read when they reach a leaf (build_tlas).
    BigVector<LeafInstance> leaf_instances;
    /// From BigVector's cache of freed blocks: a TLAS made again each frame (InstancedBvh.place)
    /// reuses the last one's memory instead of faulting in 128 bytes an instance (3,125 page faults,
    /// a few ms, at 100,000 instances while the last TLAS is still alive)
    BigVector<Instance> instances;
};

/// The settings a TLAS is built with unless told otherwise: binned SAH as for a BLAS, but one
/// instance per leaf and the report's per-primitive SAH (sah_block 1): visiting an instance means a
/// whole BLAS traversal, so leaves are never filled to save nodes.
BuildConfig default_tlas_config();

/// Checks every instance (a BLAS index within `blases`, a transform validate_transform accepts, a
/// world box within the coordinate range) and builds the TLAS. Throws std::invalid_argument naming
/// the first bad instance. `transforms[i]` places an instance of `blas_of[i]`.
Tlas build_tlas(const std::vector<const Bvh*>& blases, const std::vector<std::uint32_t>& blas_of,
                const std::vector<Transform>& transforms, const BuildConfig& config = default_tlas_config());

/// Checks instances of one BLAS, BLAS index `mesh`, as build_tlas does (transforms[i] places
/// instance index[i]): throws its std::invalid_argument, naming index[i] and `mesh`, for the first
/// it would refuse. What a change of a BLAS's geometry must pass before the TLASes over it are
/// made again.
void check_placement(const Bvh& blas, std::uint32_t mesh, const std::uint32_t* index, const Transform* transforms,
                     std::size_t count);

/// The closest hit of a two-level query: the primitive (Hit, ref and slot in the instance's BLAS)
/// and the instance. t is in world units (the ray is moved into the instance's space with its
/// direction unnormalised, so the ray parameter is the same in both). Among hits at the same t in
/// different instances, the instance visited first wins.
struct InstanceHit {
    Hit hit;
    std::uint32_t instance = kNoHit;
};

/// A TLAS with the BLASes its instances refer to (blases[i] for BLAS index i).
struct TwoLevel {
    const Tlas* tlas = nullptr;
    std::vector<BlasView> blases;
};

/// Throws std::invalid_argument unless every instance's BLAS is among scene.blases, each with a
/// tree (and, for Traversal::Wide, its wide copy).
void check_two_level(const TwoLevel& scene, Traversal mode);

/// Whether `tlas` is one identity instance, the scene the two-level queries answer with the flat
/// query of its one BLAS (the one-mesh scene of blender/motion.py's layout, without a mover).
inline bool one_identity_instance(const Tlas& tlas) { return tlas.instances.size() == 1 && tlas.instances[0].identity; }

namespace detail {
/// intersect_two_level past its one-identity-instance case: the walk through the TLAS (a scene
/// one_identity_instance rejects), out of line.
InstanceHit intersect_through_tlas(const TwoLevel& scene, const Ray& ray, Traversal mode, std::uint32_t* nodes_visited);
/// occluded_two_level past its one-identity-instance case, as intersect_through_tlas.
bool occluded_through_tlas(const TwoLevel& scene, const Ray& ray, Traversal mode);
}  // namespace detail

/// Closest hit through both levels, on a scene that check_two_level accepts. `mode` picks the BLAS
/// traversal (the TLAS is walked with a stack, stacklessly for Traversal::Stackless, and by its wide copy for
/// Traversal::Wide, whose nodes_visited counts the child boxes of each wide node visited). The ray is
/// one intersect_batch would accept. A scene of one identity instance goes straight to its BLAS:
/// exactly the flat query, tested inline so that it costs the caller little more than the flat
/// query does (design.md, "The two-level walk's cost").
inline InstanceHit intersect_two_level(const TwoLevel& scene, const Ray& ray, Traversal mode,
                                       std::uint32_t* nodes_visited = nullptr) {
    const Tlas& tlas = *scene.tlas;
    if (!one_identity_instance(tlas)) return detail::intersect_through_tlas(scene, ray, mode, nodes_visited);
    InstanceHit best;  // both flat queries give a miss t = inf
    best.hit = intersect_blas(scene.blases[tlas.instances[0].blas], ray, mode, nodes_visited);
    if (best.hit.ref != kNoHit) best.instance = 0;
    return best;
}

/// Any hit through both levels (occluded, traverse.h): the walk of intersect_two_level, ended at
/// the first instance that holds a hit before ray.tmax; exactly when intersect_two_level's t < tmax.
inline bool occluded_two_level(const TwoLevel& scene, const Ray& ray, Traversal mode) {
    const Tlas& tlas = *scene.tlas;
    if (!one_identity_instance(tlas)) return detail::occluded_through_tlas(scene, ray, mode);
    return occluded_blas(scene.blases[tlas.instances[0].blas], ray, mode);
}

/// occluded_batch over both levels (its checks, threads and cancellation).
void occluded_batch_two_level(const TwoLevel& scene, const RayBatch& rays, bool* occluded, Traversal mode,
                              std::uint32_t threads = 0, Cancellation* cancel = nullptr);

/// intersect_batch over both levels; `instance` (N, may be null) receives each hit's instance
/// (-1 on a miss). Same checks, threads and cancellation as intersect_batch.
void intersect_batch_two_level(const TwoLevel& scene, const RayBatch& rays, const HitBatch& hits,
                               std::int32_t* instance, Traversal mode, std::uint32_t threads = 0,
                               Cancellation* cancel = nullptr);

}  // namespace bvhlab
