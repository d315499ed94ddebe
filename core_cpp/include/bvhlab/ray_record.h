// ray_record.h — what one ray's traversal did, step by step (issue 35): the boxes it tested in
// order and whether each was hit, the primitives it tested, and where its closest hit lies.
#pragma once
#include <cstdint>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/ray.h"
#include "bvhlab/traverse.h"

namespace bvhlab {

/// One ray's traversal as the traversal itself saw it (the same code as intersect(), which counts
/// exactly these box tests: box_nodes.size() is its nodes_visited).
struct TraversalRecord {
    std::vector<std::uint32_t> box_nodes;      ///< nodes whose boxes were tested, in the order tested
    std::vector<std::uint8_t> box_hit;         ///< 1 where the ray entered the box
    std::vector<std::uint32_t> prim_slots;     ///< slots (Bvh::prims, leaf order) tested, in order
    std::vector<std::uint32_t> prim_leaf;      ///< the leaf each was tested in
    std::vector<std::uint32_t> prim_box_test;  ///< how many box tests came before it
    std::vector<std::uint8_t> prim_closer;     ///< 1 where it became the closest hit so far
    Hit hit;                                   ///< as intersect() returns it (t in the ray's own units)
    std::uint32_t hit_leaf = kNoHit;           ///< the leaf holding the closest hit; kNoHit on a miss
};

/// Records the traversal of `ray` (Stack or Stackless: the wide tree has no binary nodes to name).
/// The ray is checked and scaled as intersect_batch does (std::invalid_argument for a ray it refuses).
TraversalRecord record_traversal(const Bvh& bvh, Ray ray, Traversal mode);

namespace detail {
/// intersect() with every box and primitive test reported to `record` (traverse.cpp).
Hit intersect_recorded(const Bvh& bvh, const Ray& ray, Traversal mode, TraversalRecord& record);
}  // namespace detail

}  // namespace bvhlab
