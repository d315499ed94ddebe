// partition.h — dividing a range of references in two: the branch-free scatter every split
// method uses, which also gathers both sides' bounds in the same pass; sequential, or cut into
// chunks on the pool with the same result.
#pragma once
#include <limits>
#include <vector>

#include "bvhlab/split.h"

namespace bvhlab {

/// Bounds of the references one side of a partition receives: box, twice-centroid box and
/// (when asked) centroid sum, accumulated in input order.
struct SideBounds {
    F4 lo = F4::splat(std::numeric_limits<float>::infinity()), hi = F4::splat(-std::numeric_limits<float>::infinity());
    F4 c_lo = lo, c_hi = hi;
    double sum[3] = {0, 0, 0};

    template <bool kSum>
    void add(const PrimRef& p) {
        const F4 a = p.lo4(), b = p.hi4(), c = a + b;
        lo = min(lo, a), hi = max(hi, b), c_lo = min(c_lo, c), c_hi = max(c_hi, c);
        if constexpr (kSum)
            for (int k = 0; k < 3; ++k) sum[k] += 0.5 * double(p.lo[k] + p.hi[k]);
    }
    void merge(const SideBounds& o) {
        lo = min(lo, o.lo), hi = max(hi, o.hi), c_lo = min(c_lo, o.c_lo), c_hi = max(c_hi, o.c_hi);
        for (int k = 0; k < 3; ++k) sum[k] += o.sum[k];
    }
    NodeBounds finish(bool with_sum) const;
};

/// Scatter of src[r] into dst: references for which goes_left(p) holds fill dst forward from
/// `left`, the others backward from `right` (one past the last slot), each side gathering its
/// bounds. Returns the left cursor after the last reference.
template <bool kSum, class GoesLeft>
std::uint32_t scatter(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                      const GoesLeft& goes_left, SideBounds sides[2]) {
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        const PrimRef& p = src[i];
        // Select the slot with a mask, not a branch: at the top of the tree the side is a coin toss.
        const std::uint32_t l = goes_left(p) ? 1u : 0u;
        const std::uint32_t mask = 0u - l;
        dst[((right - 1) & ~mask) | (left & mask)] = p;
        left += l;
        right -= 1u - l;
        sides[1 - l].template add<kSum>(p);
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

/// Chunks of this many references: the same cut whatever the thread count, so that centroid
/// sums (added per chunk, then chunk by chunk) round the same way on any number of threads.
inline constexpr std::uint32_t kPartitionChunk = 1u << 14;

/// Partitions src[r] by goes_left and returns the first right position, with both sides' bounds
/// (sides[0] left, sides[1] right); in chunks (on the pool when ctx allows; a counting pass
/// first), with the same result as one scatter. `run(chunk, left, right, sides)` scatters one
/// chunk as scatter() does and returns its left cursor after.
template <class GoesLeft, class Run>
std::uint32_t partition_with(const SplitContext& ctx, Range r, const PrimRef* src, const GoesLeft& goes_left,
                             const Run& run, SideBounds sides[2]) {
    const std::uint32_t chunks = (r.size() + kPartitionChunk - 1) / kPartitionChunk;
    if (chunks <= 1) return run(r, r.begin, r.end, sides);
    std::vector<SideBounds> chunk_sides(2 * std::size_t(chunks));
    auto fixed = [&](std::uint32_t k) {
        return Range{r.begin + k * kPartitionChunk, std::min(r.end, r.begin + (k + 1) * kPartitionChunk)};
    };
    auto merge_sides = [&] {
        for (std::uint32_t k = 0; k < chunks; ++k)
            sides[0].merge(chunk_sides[2 * k]), sides[1].merge(chunk_sides[2 * k + 1]);
    };
    if (!ctx.parallel || ctx.parallel->threads < 2) {  // one pass, chunk after chunk
        std::uint32_t left = r.begin, right = r.end;
        for (std::uint32_t k = 0; k < chunks; ++k) {
            const Range c = fixed(k);
            const std::uint32_t end = run(c, left, right, &chunk_sides[2 * k]);
            right -= c.size() - (end - left), left = end;
            if (ctx.parallel && ctx.parallel->while_waiting) (*ctx.parallel->while_waiting)();
        }
        merge_sides();
        return left;
    }
    std::vector<std::uint32_t> left_counts(chunks), sizes(chunks);
    for_each_chunk(ctx, {0, chunks}, chunks, [&](std::uint32_t k, Range) {
        const Range c = fixed(k);
        std::uint32_t n = 0;
        for (std::uint32_t i = c.begin; i < c.end; ++i) n += goes_left(src[i]) ? 1u : 0u;
        left_counts[k] = n, sizes[k] = c.size();
    });
    const ChunkCursors cursors(r, left_counts, sizes);
    for_each_chunk(ctx, {0, chunks}, chunks, [&](std::uint32_t k, Range) {
        run(fixed(k), cursors.left[k], cursors.right[k], &chunk_sides[2 * k]);
    });
    merge_sides();
    return cursors.mid;
}

/// scatter() of the references whose twice-centroid on `axis` lies below `twice` (the mean and
/// midpoint splits): the AVX2 kernel (partition_avx2.cpp) when that path is active.
std::uint32_t scatter_below(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                            int axis, float twice, bool with_sum, SideBounds sides[2]);

}  // namespace bvhlab
