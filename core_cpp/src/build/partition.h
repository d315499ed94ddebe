// partition.h — dividing a range of references in two: the branch-free scatter every split
// method uses, sequential or cut into chunks on the pool with the same result.
#pragma once
#include <vector>

#include "bvhlab/split.h"

namespace bvhlab {

/// Scatter of src[r] into dst: references for which goes_left(p) holds fill dst forward from
/// `left`, the others backward from `right` (one past the last slot), both in input order from
/// their end. Returns the left cursor after the last reference.
template <class GoesLeft>
std::uint32_t scatter(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                      const GoesLeft& goes_left) {
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        const PrimRef& p = src[i];
        // Select the slot with a mask, not a branch: at the top of the tree the side is a coin toss.
        const std::uint32_t l = goes_left(p) ? 1u : 0u;
        const std::uint32_t mask = 0u - l;
        dst[((right - 1) & ~mask) | (left & mask)] = p;
        left += l;
        right -= 1u - l;
    }
    return left;
}

/// Where chunk k of a chunked scatter writes: its left part starts at left[k], its right part
/// ends at right[k]. With these, the chunks together write exactly what one scatter over the
/// whole range writes.
struct ChunkCursors {
    std::vector<std::uint32_t> left, right;
    std::uint32_t mid = 0;
    ChunkCursors(Range r, const std::vector<std::uint32_t>& left_counts, const std::vector<std::uint32_t>& sizes) {
        left.resize(left_counts.size()), right.resize(left_counts.size());
        std::uint32_t l = r.begin, rr = r.end;
        for (std::size_t k = 0; k < left_counts.size(); ++k) {
            left[k] = l, right[k] = rr;
            l += left_counts[k], rr -= sizes[k] - left_counts[k];
        }
        mid = l;
    }
};

/// Partitions src[r] into dst[r] by goes_left and returns the first right position; in chunks
/// on the pool when ctx allows (a counting pass first), with the same result as one scatter.
template <class GoesLeft>
std::uint32_t partition(const SplitContext& ctx, Range r, const PrimRef* src, PrimRef* dst, const GoesLeft& goes_left) {
    const std::uint32_t chunks = chunk_count(ctx, r);
    if (chunks == 1) return scatter(src, dst, r, r.begin, r.end, goes_left);
    std::vector<std::uint32_t> left_counts(chunks), sizes(chunks);
    for_each_chunk(ctx, r, chunks, [&](std::uint32_t k, Range c) {
        std::uint32_t n = 0;
        for (std::uint32_t i = c.begin; i < c.end; ++i) n += goes_left(src[i]) ? 1u : 0u;
        left_counts[k] = n, sizes[k] = c.size();
    });
    ChunkCursors cursors(r, left_counts, sizes);
    for_each_chunk(ctx, r, chunks, [&](std::uint32_t k, Range c) {
        scatter(src, dst, c, cursors.left[k], cursors.right[k], goes_left);
    });
    return cursors.mid;
}

}  // namespace bvhlab
