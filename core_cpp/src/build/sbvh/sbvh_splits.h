// sbvh_splits.h — the two candidate splits of an SBVH node (Stich, Friedrich and Dietrich 2009
// §4): the binned SAH object split over the references' centroids, and the spatial split over
// equal bins of the node's box with each reference chopped into the bins it spans (chop.h).
#pragma once
#include <cstdint>
#include <limits>

#include "bvhlab/geometry.h"
#include "bvhlab/prim_ref.h"
#include "bvhlab/sah.h"

namespace bvhlab::sbvh {

/// The cheapest object split: references whose centroid bin is below `bin` on `axis` go left.
struct ObjectSplit {
    float cost = std::numeric_limits<float>::infinity();
    int axis = -1;  ///< -1: none (every centroid in one bin on every axis)
    std::uint32_t bin = 0;
    Aabb left, right;  ///< the children's boxes
};

/// The cheapest spatial split: the plane x[axis] = position; `left`/`right` and the counts are the
/// bins' (chopped boxes; a reference that straddles counts on both sides).
struct SpatialSplit {
    float cost = std::numeric_limits<float>::infinity();
    int axis = -1;  ///< -1: none
    float position = 0;
    Aabb left, right;
    std::uint32_t left_count = 0, right_count = 0;
};

/// The most bins of a spatial split (tinybvh's BuildHQ uses 8 too): each reference is clipped into
/// every bin it spans, so the bins' count is the spatial split's cost. On Sponza 8 gave a lower SAH
/// than 12 (61.9 against 63.9) at 16% fewer instructions; 6 and 4 fewer still, SAH 64.3 and 63.8.
constexpr std::uint32_t kMaxSpatialBins = 8;

/// How a node's references are binned: `bins` buckets per axis for the object split
/// (BuildConfig::bins), `spatial_bins` (at most kMaxSpatialBins of them) for the spatial split, and the SAH.
struct BinSetup {
    std::uint32_t bins, spatial_bins;
    SahCost sah;
};

/// Best object split of refs[0, n) by their centroids in equal bins of `span` (the node's box or
/// its centroid bounds: BuildConfig::bin_bounds), parent half area `area`.
ObjectSplit find_object_split(const PrimRef* refs, std::uint32_t n, const Aabb& span, float area,
                              const BinSetup& setup);

/// Best spatial split of refs[0, n) inside the node's box `box`.
SpatialSplit find_spatial_split(const GeometryView& g, const PrimRef* refs, std::uint32_t n, const Aabb& box,
                                const BinSetup& setup);

/// The bin of coordinate x among `bins` equal bins from `lo` with bins / extent = `scale`.
inline std::uint32_t bin_of(float x, float lo, float scale, std::uint32_t bins) {
    return truncate_clamped((x - lo) * scale, float(bins - 1));
}

}  // namespace bvhlab::sbvh

namespace bvhlab::sbvh {

/// The side of `r` under object split `s` found over `span` (the binning of find_object_split, so
/// both agree on every reference).
inline bool object_goes_left(const PrimRef& r, const ObjectSplit& s, const Aabb& span, std::uint32_t bins) {
    const float extent = span.extent()[s.axis];
    return bin_of(r.centroid(s.axis), span.lo[s.axis], float(bins) / extent, bins) < s.bin;
}

}  // namespace bvhlab::sbvh
