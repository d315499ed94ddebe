// ray_record.h — what one ray's traversal did, step by step (issue 35): the boxes it tested in
// order and whether each was hit, the primitives it tested, and where its closest hit lies.
#pragma once
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/ray.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"

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
    /// What intersect() reports as nodes_visited: the box tests (Stack, Stackless), or the wide
    /// nodes visited (Wide: each tests its up to eight children's boxes at once)
    std::uint32_t nodes_visited = 0;
    /// Wide only: the binary node each visited wide node stands for (the top of the binary nodes
    /// collapsed into it), in the order visited; nodes_visited is its size
    std::vector<std::uint32_t> wide_nodes;
    /// Wide only: for each box test (a child slot of a visited wide node), that node's position in
    /// wide_nodes
    std::vector<std::uint32_t> box_wide_step;
};

/// The primitives a recorded walk passes by as if they were not there, as the tracer passes a
/// surface whose material hides from its rays (Material.hidden_from; traverse.glsl `sees`):
/// hides(mesh, ref) for primitive `ref` of mesh `mesh`'s tree (0 for a flat tree). Empty: none.
using HiddenPrims = std::function<bool(std::uint32_t mesh, std::uint32_t ref)>;

/// Records the traversal of `ray` (Stack or Stackless; the wide walk is record_wide_traversal),
/// passing by the primitives `hidden` names. The ray is checked and scaled as intersect_batch
/// does (std::invalid_argument for a ray it refuses).
TraversalRecord record_traversal(const Bvh& bvh, Ray ray, Traversal mode, const HiddenPrims& hidden = {});

/// Which binary node each node and leaf of a wide tree (wide_bvh.h) stands for, by line: a wide
/// node's line, or a leaf's first packet's. A wide node stands for the binary node it was made
/// from, a leaf for the binary subtree it holds (at most four primitives), each found by its
/// primitives' range in leaf order, which no two binary nodes share (make_wide's layout is not
/// assumed).
struct WideNames {
    std::unordered_map<std::uint32_t, std::uint32_t> binary_of_line;
    std::uint32_t at(std::uint32_t line) const { return binary_of_line.at(line); }
};
WideNames name_wide_nodes(const Bvh& bvh, const WideBvh& wide);

/// Records the walk of the wide tree that intersect_wide runs (the same kernel of the same
/// instruction set path, in its recorded instantiation, wide_traverse.inl), its steps named by
/// binary nodes (`names`, of this wide tree): each wide node visited (wide_nodes), each child box
/// it tested (box_nodes, box_hit, box_wide_step), each primitive of each leaf entered. The ray is
/// checked and scaled as record_traversal's.
TraversalRecord record_wide_traversal(const Bvh& bvh, const WideBvh& wide, const WideNames& names, Ray ray);

namespace detail {
/// intersect() with every box and primitive test reported to `record` (traverse.cpp); a primitive
/// `hidden` names (as primitive of mesh `mesh`) is tested but never taken as the hit.
Hit intersect_recorded(const Bvh& bvh, const Ray& ray, Traversal mode, TraversalRecord& record,
                       const HiddenPrims& hidden = {}, std::uint32_t mesh = 0);
/// intersect_wide() recorded into `record` (wide_record.cpp); the ray already scaled, t as the walk
/// returns it.
Hit intersect_wide_recorded(const Bvh& bvh, const WideBvh& wide, const WideNames& names, const Ray& ray,
                            TraversalRecord& record);
}  // namespace detail

}  // namespace bvhlab
