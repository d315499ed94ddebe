// assemble.h — the subtrees of a parallel build spliced into one depth-first array.
#pragma once
#include <vector>

#include "subtree_builder.h"

namespace bvhlab {

/// Box of every internal node of `nodes` (a depth-first subtree whose root is at 0): the union of
/// its children's, for the methods that make boxes from the leaves up (LBVH); the skip index is
/// written again with it (the skip of the second child; the builder wrote them all already,
/// SubtreeWriter::close_spine).
void fill_boxes_from_children(BigVector<BvhNode>& nodes);

/// Splices the subtrees of the deferred ranges (top.parts, skip indices filled where they have no
/// placeholders of their own, their parts spliced into them likewise) into the placeholders of
/// `top`, keeping depth-first order, and fills the skip indices of the nodes of every subtree
/// with placeholders. Each subtree is copied once, on up to `threads` threads.
void assemble(const Subtree& top, unsigned threads, bool boxes_from_children, Bvh& out);

}  // namespace bvhlab
