// linked_tree.h — a tree as linked nodes (parent and both children by index) for restructuring:
// the flattened depth-first array (docs/design.md "Tree layout") cannot move a subtree without
// rewriting every index after it. Converted from a Bvh and back.
#pragma once
#include <cstdint>
#include <vector>

#include "bvhlab/aabb.h"
#include "bvhlab/bvh.h"

namespace bvhlab::optimize {

inline constexpr std::uint32_t kNone = 0xffffffffu;

struct LinkedNode {
    Aabb box;
    std::uint32_t parent = kNone, left = kNone, right = kNone;  ///< children of an internal node
    std::uint32_t first = 0, count = 0;  ///< a leaf's slots in the source tree's refs; count 0: internal
    std::uint32_t height = 1;            ///< levels of its subtree (a leaf: 1)

    bool leaf() const { return count != 0; }
};

struct LinkedTree {
    std::vector<LinkedNode> nodes;
    std::uint32_t root = kNone;
};

/// Node i of `bvh` becomes node i of the linked tree (leaves keep their slots).
LinkedTree link(const Bvh& bvh);

/// `tree` flattened depth-first (first child = left) into a Bvh with `source`'s references, packed
/// primitives, counts, fingerprint and settings, leaves' slots renumbered in leaf order. With
/// `merge`, each topmost subtree of at most source.config.max_leaf_size primitives whose SAH cost
/// as one leaf is lower than as it stands becomes one leaf; `merged` counts them.
Bvh flatten(const LinkedTree& tree, const Bvh& source, bool merge, std::uint64_t* merged = nullptr);

}  // namespace bvhlab::optimize
