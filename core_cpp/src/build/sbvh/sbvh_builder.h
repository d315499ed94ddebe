// sbvh_builder.h — the SBVH builder (Stich, Friedrich and Dietrich 2009, "Spatial Splits in
// Bounding Volume Hierarchies"): build_bvh calls it for SplitMethod::Sbvh.
#pragma once
#include <atomic>
#include <cstdint>

#include "bvhlab/bvh.h"
#include "bvhlab/cancel.h"

namespace bvhlab {

/// Builds out.nodes, refs, depths and prims over the primitive references `refs` (make_prim_refs'):
/// at each node the binned SAH object split, and where
/// its children overlap by more than sbvh_alpha of the root's area (and references are left in
/// the budget) the spatial split with chopped references; the cheaper wins, or a leaf. One thread,
/// so the tree never depends on the thread count. Returns early, the tree unfinished, when
/// `cancel` says stop (the caller checks it). `in_leaves` counts primitives placed, for progress.
void build_sbvh(const BigVector<PrimRef>& refs, const GeometryView& geometry, const BuildConfig& config,
                Cancellation& cancel, std::atomic<std::uint64_t>& in_leaves, Bvh& out);

}  // namespace bvhlab
