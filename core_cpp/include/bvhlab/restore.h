// restore.h — a tree made again from its saved nodes and references over the geometry it was
// built for (issue 35: trees saved to files), every invariant of docs/design.md "Tree layout"
// checked first, so that no file, however made, gives a tree the traversals could misread.
#pragma once
#include <cstdint>
#include <vector>

#include "bvhlab/bvh.h"

namespace bvhlab {

/// What a saved tree holds besides the geometry.
struct SavedTree {
    std::vector<BvhNode> nodes;       ///< depth-first, root at 0 (bvh.h)
    std::vector<std::uint32_t> refs;  ///< primitive references in leaf order
    std::uint64_t geometry_fingerprint = 0;
    BuildConfig config;
    double build_ms = 0;
};

/// The tree of `saved` over `geometry`, its leaf-ordered geometry packed again. Throws
/// std::invalid_argument when the geometry's fingerprint differs from the saved one (another
/// scene, or the same scene changed), or when the nodes and references are not a tree over it:
/// a node or child out of range, children not in depth-first order, a wrong skip index, a leaf
/// that is empty or whose slots do not follow the previous leaf's, a reference out of range or
/// used twice, a box that is not finite or does not hold its children or primitives (an SBVH's
/// leaves' boxes together all of each primitive: inspect/coverage.h), a tree
/// deeper than MAX_TREE_HEIGHT, a scene with triangles too small to trace (check_extent, as the build
/// refuses it). O(nodes + primitives), an SBVH's references sorted by primitive
/// and its many-part primitives clipped by their parts' boxes (coverage.h); no recursion.
Bvh restore_bvh(SavedTree saved, const GeometryView& geometry, unsigned threads = 0);

}  // namespace bvhlab
