// An independent check of every structural invariant of a built tree (docs/design.md, "Tree layout").
#pragma once
#include <gtest/gtest.h>

#include <functional>
#include <cstring>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/stats.h"

namespace bvhlab::test {

using bvhlab::prim_box;  // the core's (geometry.h)

/// Walks the tree recursively (the builder never recurses, so this is an independent view) and
/// checks layout, boxes, skip indices, depths and counts. Returns the subtree's end index.
inline std::uint32_t check_subtree(const Bvh& bvh, const GeometryView& g, std::uint32_t i, std::uint32_t depth,
                                   std::vector<int>& seen) {
    const BvhNode& n = bvh.nodes.at(i);
    EXPECT_EQ(bvh.depths.at(i), depth) << "node " << i;
    Aabb box = node_box(n);
    if (is_leaf(n)) {
        EXPECT_GE(leaf_count(n), 1u);
        for (std::uint32_t k = n.index; k < n.index + leaf_count(n); ++k) {
            std::uint32_t ref = bvh.refs.at(k);
            std::size_t slot = (ref & gpu::REF_INDEX_MASK) + ((ref & gpu::REF_SPHERE_BIT) ? g.triangle_count : 0);
            ++seen.at(slot);
            EXPECT_TRUE(box.contains(prim_box(g, ref))) << "leaf " << i << " misses primitive " << ref;
            const PackedPrim expected = pack_prim(g, ref);  // the leaf-ordered geometry, byte for byte
            EXPECT_EQ(std::memcmp(&bvh.prims.at(k), &expected, sizeof(PackedPrim)), 0) << "packed primitive " << k;
        }
        return i + 1;
    }
    std::uint32_t first = i + 1, second = n.index;
    EXPECT_TRUE(box.contains(node_box(bvh.nodes.at(first)))) << "node " << i;
    EXPECT_TRUE(box.contains(node_box(bvh.nodes.at(second)))) << "node " << i;
    std::uint32_t end_first = check_subtree(bvh, g, first, depth + 1, seen);
    EXPECT_EQ(end_first, second) << "second child of " << i << " must follow the first subtree";
    std::uint32_t end = check_subtree(bvh, g, second, depth + 1, seen);
    EXPECT_EQ(skip_index(n, i), end) << "skip index of node " << i;
    return end;
}

inline void check_tree(const Bvh& bvh, const GeometryView& g, std::uint32_t max_leaf_size) {
    const std::size_t n_prims = g.primitive_count();
    ASSERT_EQ(bvh.refs.size(), n_prims);
    ASSERT_EQ(bvh.depths.size(), bvh.nodes.size());
    if (n_prims == 0) {
        EXPECT_TRUE(bvh.nodes.empty());
        return;
    }
    std::vector<int> seen(n_prims, 0);
    EXPECT_EQ(check_subtree(bvh, g, 0, 0, seen), bvh.nodes.size());
    for (std::size_t k = 0; k < n_prims; ++k) ASSERT_EQ(seen[k], 1) << "primitive slot " << k;

    BvhStats s = compute_stats(bvh);
    EXPECT_EQ(s.nodes, 2 * s.leaves - 1);
    EXPECT_LE(s.height, gpu::MAX_TREE_HEIGHT);
    EXPECT_LE(s.max_leaf_size, max_leaf_size);
    std::uint64_t total = 0, leaves = 0;
    for (auto c : s.nodes_per_depth) total += c;
    for (std::size_t k = 0; k < s.leaf_size_histogram.size(); ++k) leaves += s.leaf_size_histogram[k];
    EXPECT_EQ(total, s.nodes);
    EXPECT_EQ(leaves, s.leaves);
    EXPECT_EQ(s.nodes_per_depth.size(), s.height);
}

}  // namespace bvhlab::test
