// morton.h — Morton codes of centroids and the radix sort behind the LBVH split method.
#pragma once
#include <vector>
#include "bvhlab/big_vector.h"
#include "bvhlab/cancel.h"
#include "bvhlab/prim_ref.h"

namespace bvhlab {

/// Stores in each ref's `code` the 30-bit Morton code (10 bits per axis) of its centroid within
/// `centroid_bounds`, then sorts the refs by code (a stable radix sort: ties keep input order), on
/// up to `threads` threads of the pool. Polls `cancel` (if set) on the calling thread between
/// tasks; once a stop is asked, it returns with the refs as they were.
void sort_by_morton_code(BigVector<PrimRef>& refs, const Aabb& centroid_bounds, unsigned threads, Cancellation* cancel);

}  // namespace bvhlab
