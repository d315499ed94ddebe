// pair_nodes.h — the tree's internal nodes with both children's boxes (gpu::BvhPair), the node
// format of the tracer's stack walk (shaders/tracer/traverse.glsl).
#pragma once
#include "bvhlab/big_vector.h"
#include "bvhlab/bvh.h"
#include "gpu_types.h"

namespace bvhlab {

/// One BvhPair per internal node of `bvh`, in depth-first order (the root's is pair 0); empty for
/// an empty tree or one whose root is a leaf. Each child's box, pair index or leaf range is the
/// tree's, copied: the same tree in another layout (Aila and Laine 2009). Throws
/// std::invalid_argument for nodes that are not a depth-first binary tree, or a leaf whose first
/// slot needs bit 31 (PAIR_LEAF_BIT). A copy: a refit of `bvh` leaves it behind.
BigVector<gpu::BvhPair> make_pair_nodes(const Bvh& bvh);

}  // namespace bvhlab
