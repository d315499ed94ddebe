// small_subtree.h — the last levels of the SAH methods' trees: a range of at most
// small_subtree_size(config) references (split.h) is read once, sorted once on each axis, and
// its whole subtree built with the exact SAH of every split position (report §2.3.2, the sweep
// the report describes before it turns to buckets). This is the full-sweep SAH builder of Wald,
// Boulos and Shirley ("Ray Tracing Deformable Scenes Using Dynamic Bounding Volume Hierarchies",
// ACM TOG 26(1), 2007) in miniature, with the three sorted orders kept sorted through each split
// by a stable partition instead of sorted again at every node (as Wald and Havran keep their
// event lists: "On building fast kd-trees for ray tracing, and on doing that in O(N log N)",
// IEEE RT 2006), and the three axes swept at once, one vector lane each. On Sponza and 1M
// triangles it builds these levels in fewer instructions than binning them, and finds the
// optimum where 8 buckets only approximate it.
#pragma once
#include "subtree_writer.h"

namespace bvhlab {

/// Builds the subtree of `item` (2..small_subtree_size(cfg) references; its node is already open at
/// `index`): the exact SAH on the axes the policy allows, leaves where the SAH finds them
/// cheaper (at most max_leaf_size), an even split where every centroid coincides, median splits
/// where the tree would outgrow the GPU stack (too_deep). Reads the references, never moves them.
void build_small_subtree(SubtreeWriter& writer, const BuildConfig& cfg, const WorkItem& item, std::uint32_t index);

}  // namespace bvhlab
