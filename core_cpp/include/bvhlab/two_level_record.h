// two_level_record.h — one ray's walk through a two-level tree (tlas.h), recorded by the walk
// itself (traverse_two_level.cpp): the TLAS's box tests, and for each instance the ray entered,
// that instance's BLAS walk (ray_record.h), with its instance.
#pragma once
#include <cstdint>
#include <vector>

#include "bvhlab/ray_record.h"
#include "bvhlab/tlas.h"

namespace bvhlab {

/// A two-level walk as it happened. nodes_visited is what intersect_two_level reports for the ray:
/// the TLAS's box tests plus each BLAS walk's nodes_visited.
struct TwoLevelRecord {
    /// The TLAS walk: its box tests (TLAS nodes; Traversal::Wide tests the children of each wide
    /// TLAS node visited, each named by its binary node); its primitive tests are the instances entered,
    /// in order: prim_slots holds the instance, prim_leaf the TLAS leaf (kNoHit in a scene of one
    /// identity instance, which has no TLAS walk: intersect_two_level), prim_closer whether the
    /// instance held a hit nearer than the closest so far
    TraversalRecord tlas;
    /// Per instance entered (as tlas.prim_slots), its BLAS walk: the object-space ray's steps,
    /// with nodes and slots of the instance's mesh tree; hit t in the world ray's units
    std::vector<TraversalRecord> blas;
    InstanceHit hit;                       ///< as intersect_two_level returns it
    std::uint32_t hit_leaf = kNoHit;       ///< the leaf of the hit instance's BLAS holding the hit
    std::uint32_t hit_tlas_leaf = kNoHit;  ///< the TLAS leaf of the hit instance
    std::uint32_t nodes_visited = 0;
};

/// Records the walk of `ray` (checked and scaled as intersect_batch_two_level does) through a
/// scene check_two_level accepts. Traversal::Wide needs `wide_names[b]` (name_wide_nodes of BLAS
/// b's wide tree) for every BLAS b; the other traversals ignore it. The BLAS walks pass by the
/// primitives `hidden` names (its mesh: the BLAS's index); not with Traversal::Wide
/// (std::invalid_argument).
TwoLevelRecord record_two_level(const TwoLevel& scene, Ray ray, Traversal mode,
                                const std::vector<const WideNames*>& wide_names = {}, const HiddenPrims& hidden = {});

/// What the two-level walk reports when recorded (traverse_two_level.cpp calls it).
class TwoLevelRecorder {
public:
    /// A TLAS box test.
    virtual void box(std::uint32_t node, bool entered) = 0;
    /// Instance `index` of TLAS leaf `leaf` is entered with the object-space ray `ray` (scaled):
    /// walks and records its BLAS as the query's walk would, returning the hit (t in the object
    /// ray's units) and, in `visited`, the walk's nodes_visited.
    virtual Hit instance(std::uint32_t leaf, std::uint32_t index, const BlasView& blas, const Ray& ray, Traversal mode,
                         std::uint32_t* visited) = 0;
    /// The instance just entered held a hit nearer than the closest so far (or not); `t_scale`
    /// takes its object ray's t to the world ray's.
    virtual void instance_done(bool closer, float t_scale) = 0;

protected:
    ~TwoLevelRecorder() = default;
};

namespace detail {
/// intersect_two_level with every step reported to `recorder`.
InstanceHit intersect_two_level_recorded(const TwoLevel& scene, const Ray& ray, Traversal mode,
                                         TwoLevelRecorder& recorder, std::uint32_t* nodes_visited);
}  // namespace detail

}  // namespace bvhlab
