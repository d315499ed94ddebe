// morton.h — Morton codes of centroids and the radix sort behind the LBVH split method.
#pragma once
#include <vector>
#include "bvhlab/big_vector.h"
#include "bvhlab/prim_ref.h"

namespace bvhlab {

/// Stores in each ref's `code` the 30-bit Morton code (10 bits per axis) of its centroid within
/// `centroid_bounds`, then sorts the refs by code (stable LSD radix sort: ties keep input order).
void sort_by_morton_code(BigVector<PrimRef>& refs, const Aabb& centroid_bounds);

}  // namespace bvhlab
