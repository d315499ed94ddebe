// assemble.h — the subtrees of a parallel build spliced into one depth-first array.
#pragma once
#include <vector>

#include "subtree_builder.h"

namespace bvhlab {

/// Skip index of every internal node of `nodes` (a depth-first subtree whose root is at 0): the
/// skip of its second child; leaves skip to i + 1, the last nodes to nodes.size(). With
/// `boxes_from_children`, also each internal node's box: the union of its children's. The
/// builder writes skip indices as it goes (SubtreeWriter::close_spine); this pass is for the
/// methods that make boxes from the leaves up (LBVH).
void fill_skip_indices(BigVector<BvhNode>& nodes, bool boxes_from_children);

/// Splices the deferred subtrees (`parts`, skip indices filled) into the placeholders of `top`,
/// keeping depth-first order, and fills the skip indices of the top nodes. The parts are copied
/// on up to `threads` threads.
void assemble(const Subtree& top, const std::vector<Subtree>& parts, unsigned threads, bool boxes_from_children,
              Bvh& out);

}  // namespace bvhlab
