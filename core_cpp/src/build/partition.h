// partition.h — dividing a range of references in two: the branch-free scatter every split
// method uses, sequential, or cut into chunks on the pool with the same result. The scatter only
// moves references; the children's bounds are gathered afterwards, in one pass over each side's
// contiguous positions (bounds_of), which costs fewer instructions than sorting every reference's
// box into one of two accumulators as it moves.
#pragma once
#include <cstring>
#include <vector>

#include "bvhlab/split.h"

namespace bvhlab {

/// Scatter of src[r] into dst: references for which goes_left(src[i], i) holds fill dst forward
/// from `left`, the others backward from `right` (one past the last slot). Returns the left
/// cursor after the last reference. `Move` loads a reference into registers and stores it.
///
/// kContained: every write lands in the slots this scatter fills (one store per reference, at
/// a slot chosen by mask). Otherwise each reference is stored at both cursors, without a select;
/// the store at the wrong cursor writes the slot next to the part filled so far (at most one past
/// either part's end), which a later reference of the same scatter overwrites — so scatters of
/// consecutive chunks of one range run in order, never at once.
///
/// A template only on types local to the file that instantiates it (below), and calling nothing
/// but those: the AVX2 file instantiates it too (see binning_avx2.cpp on inline functions).
template <bool kContained, class Move, class GoesLeft>
std::uint32_t scatter(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                      const GoesLeft& goes_left) {
    // Cursors in bytes, and a reference's side as 0 or sizeof(PrimRef): two adds per reference.
    constexpr std::uintptr_t kSize = sizeof(PrimRef);
    std::uintptr_t next_left = reinterpret_cast<std::uintptr_t>(dst + left);
    std::uintptr_t last_right = reinterpret_cast<std::uintptr_t>(dst + right) - kSize;
    auto move = [&](const PrimRef* from, std::uintptr_t left_bytes) {  // left_bytes: kSize or 0
        const auto p = Move::load(from);
        if constexpr (kContained) {  // a select, not a branch: at the top of the tree the side is a coin toss
            Move::store(reinterpret_cast<PrimRef*>(left_bytes ? next_left : last_right), p);
        } else {
            Move::store(reinterpret_cast<PrimRef*>(next_left), p);
            Move::store(reinterpret_cast<PrimRef*>(last_right), p);
        }
        next_left += left_bytes;
        last_right += left_bytes - kSize;
    };
    std::uint32_t i = r.begin;
    if constexpr (requires { goes_left.eight(src, i); })  // the sides of eight at once: bit j for i + j
        for (; i + 8 <= r.end; i += 8) {
            std::uintptr_t bits = std::uintptr_t(goes_left.eight(src, i)) * kSize;
            for (std::uint32_t j = 0; j < 8; ++j, bits >>= 1) move(src + i + j, bits & kSize);
        }
    for (; i < r.end; ++i) move(src + i, goes_left(src[i], i) ? kSize : 0);
    return std::uint32_t((reinterpret_cast<PrimRef*>(next_left)) - dst);
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

/// Whether the chunks of a pass run in turn on the calling thread (one chunk, or one thread).
inline bool chunks_in_turn(const SplitContext& ctx, std::uint32_t chunks) {
    return chunks <= 1 || !ctx.parallel || ctx.parallel->threads < 2;
}

/// The chunks of r, one after the other on the calling thread: `run(chunk, left, right)` scatters
/// one chunk from the cursors the last one left (so no counting pass) and returns its left cursor
/// after; the cancellation is polled between chunks. Returns the first right position.
template <class Run>
std::uint32_t scatter_in_turn(const SplitContext& ctx, Range r, std::uint32_t chunks, const Run& run) {
    std::uint32_t left = r.begin, right = r.end;
    for (std::uint32_t k = 0; k < chunks; ++k) {
        const Range c = chunk_of(r, k, chunks);
        const std::uint32_t end = run(c, left, right);
        right -= c.size() - (end - left), left = end;
        if (k + 1 < chunks && ctx.parallel && ctx.parallel->while_waiting) (*ctx.parallel->while_waiting)();
    }
    return left;
}

/// Partitions src[r] by goes_left(ref, position) and returns the first right position. Large
/// ranges on the pool: a counting pass, then chunks scattered at once (contained stores); else one
/// scatter. `run(chunk, left, right, contained)` scatters one chunk as scatter() does and returns
/// its left cursor after. The result never depends on the threads.
template <class GoesLeft, class Run>
std::uint32_t partition_with(const SplitContext& ctx, Range r, const PrimRef* src, const GoesLeft& goes_left,
                             const Run& run) {
    const std::uint32_t chunks = chunk_count(ctx, r);
    if (chunks_in_turn(ctx, chunks))
        return scatter_in_turn(ctx, r, chunks, [&](Range c, std::uint32_t left, std::uint32_t right) {
            return run(c, left, right, false);
        });
    std::vector<std::uint32_t> left_counts(chunks), sizes(chunks);
    for_each_chunk(ctx, r, chunks, [&](std::uint32_t k, Range c) {
        std::uint32_t n = 0;
        for (std::uint32_t i = c.begin; i < c.end; ++i) n += goes_left(src[i], i) ? 1u : 0u;
        left_counts[k] = n, sizes[k] = c.size();
    });
    const ChunkCursors cursors(r, left_counts, sizes);
    for_each_chunk(ctx, r, chunks, [&](std::uint32_t k, Range c) { run(c, cursors.left[k], cursors.right[k], true); });
    return cursors.mid;
}

/// scatter() of the references whose twice-centroid on `axis` lies below `twice` (the mean and
/// midpoint splits): the AVX2 kernel (partition_avx2.cpp) when that path is active.
std::uint32_t scatter_below(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                            int axis, float twice, bool contained);

/// Bounds of one run of references as plain numbers: box, twice-centroid box, and the sum of the
/// twice-centroids (lane 3 unused). bounds_of merges the runs of fixed blocks in order.
struct RunBounds {
    alignas(16) float lo[4], hi[4], clo[4], chi[4];
    alignas(16) double sum[4];
};
/// The bounds of refs[r] (with the sums when asked), even and odd positions from r.begin in two
/// sets of accumulators merged at the end: the AVX2 kernel (partition_avx2.cpp) computes the same.
void run_bounds(const PrimRef* refs, Range r, bool with_sum, RunBounds& out);

/// The median's histogram (split_median.cpp): the bucket of a reference is its twice-centroid on
/// `axis`, less `origin`, times `scale`, clamped to [0, top] and truncated — monotone in the
/// centroid. count_buckets writes each reference's bucket to tag[i - r.begin] and counts them in
/// count[0..top] (zeroed by the caller): the AVX2 kernel (partition_avx2.cpp) when active.
struct Bucketing {
    float origin, scale, top;
    int axis;
};
void count_buckets(const PrimRef* src, Range r, const Bucketing& b, std::uint16_t* tag, std::uint32_t* count);

/// The median's sides (split_median.cpp): the reference at position i goes left when
/// tag[i - base] <= last_left.
struct SideTags {
    const std::uint16_t* tag;
    std::uint32_t base;
    std::uint32_t last_left;
};
std::uint32_t scatter_tagged(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                             const SideTags& tags, bool contained);

// The predicates of the two scatters, for the portable and the AVX2 file alike. In an unnamed
// namespace, so that each file instantiates scatter() with its own copy (compiled for its ISA).
namespace {

/// Moves a reference as plain bytes (the portable path).
struct MoveBytes {
    static PrimRef load(const PrimRef* p) {
        PrimRef v;
        std::memcpy(&v, p, sizeof v);
        return v;
    }
    static void store(PrimRef* p, const PrimRef& v) { std::memcpy(p, &v, sizeof v); }
};

/// Twice-centroid on `axis` below `twice` (mean and midpoint).
struct BelowTwice {
    int axis;
    float twice;
    bool operator()(const PrimRef& p, std::uint32_t) const { return p.lo[axis] + p.hi[axis] < twice; }
};

/// Tagged for the left side (the median).
struct TaggedLeft {
    SideTags t;
    bool operator()(const PrimRef&, std::uint32_t i) const { return t.tag[i - t.base] <= t.last_left; }
};

}  // namespace

}  // namespace bvhlab
