// Binned SAH (report §2.3.2, PBRT §4.3.2): B equal buckets per axis, the cheapest bucket
// boundary by an O(B) sweep (the improvement the report names over its O(n + B²) loop), then one
// pass that scatters by bucket and fills the children's buckets (binning.h). At the top of the
// tree the passes run in chunks on every thread.
#include <algorithm>

#include "binning.h"
#include "partition.h"

namespace bvhlab {
namespace {

BinStore& store_of(SplitContext& ctx) {
    if (!ctx.scratch.bins) ctx.scratch.bins = std::make_unique<BinStore>(ctx.config.bins);
    return *ctx.scratch.bins;
}

/// The buckets of a node its parent did not bin: one pass of its own (in chunks at the top).
BinSet bin_node(SplitContext& ctx, Range r, const PrimRef* in, const BinFrame& f) {
    BinStore& store = store_of(ctx);
    const std::uint32_t chunks = chunk_count(ctx, r);
    for (std::uint32_t k = 0; k < 2 * chunks; ++k) store.slot(kChunkSlots + k).reset();
    for_each_chunk(ctx, r, chunks, [&](std::uint32_t k, Range c) {
        const BinSet copies[2] = {store.slot(kChunkSlots + 2 * k), store.slot(kChunkSlots + 2 * k + 1)};
        bin_refs(in, c, f, copies);
    });
    const BinSet own = store.slot(kOwnSlot);
    own.reset();
    for (std::uint32_t k = 0; k < 2 * chunks; ++k) own.merge(store.slot(kChunkSlots + k));
    return own;
}

/// The fused pass over r on the calling thread, its `chunks` pieces in turn (scatter_in_turn):
/// the children's buckets end up in their slots.
std::uint32_t partition_whole(SplitContext& ctx, Range r, int src, const BinFrame& f, const BinSplit& best,
                              ChildBinning child[2], const std::int32_t slots[2], CentroidBounds sides[2],
                              std::uint32_t chunks) {
    BinStore& store = store_of(ctx);
    BinSet copies[2][2];
    for (int s = 0; s < 2; ++s) {
        if (slots[s] < 0) continue;
        copies[s][0] = store.slot(std::uint32_t(slots[s])), copies[s][1] = store.slot(kChunkSlots + s);
        copies[s][0].reset(), copies[s][1].reset();
        child[s].copies = copies[s];
    }
    const std::uint32_t mid = scatter_in_turn(ctx, r, chunks, [&](Range c, std::uint32_t left, std::uint32_t right) {
        return partition_and_bin(ctx.buffers[src], ctx.buffers[1 - src], c, left, right, f, best, child, sides);
    });
    for (int s = 0; s < 2; ++s)
        if (slots[s] >= 0) copies[s][0].merge(copies[s][1]);
    return mid;
}

/// The fused pass in chunks on the pool (the top of the tree): a counting pass first finds where
/// each chunk writes; each chunk fills buckets of its own, merged into the slots after.
std::uint32_t partition_chunks(SplitContext& ctx, Range r, int src, const BinFrame& f, const BinSplit& best,
                               const ChildBinning child[2], const std::int32_t slots[2], CentroidBounds sides[2],
                               std::uint32_t chunks) {
    BinStore& store = store_of(ctx);
    const PrimRef* in = ctx.buffers[src];
    std::vector<BinSet> copies(4 * std::size_t(chunks));  // per chunk: left ×2, right ×2
    for (std::uint32_t k = 0; k < 4 * chunks; ++k)
        if (slots[(k / 2) % 2] >= 0) (copies[k] = store.slot(kChunkSlots + k)).reset();
    std::vector<std::uint32_t> left_counts(chunks), sizes(chunks);
    for_each_chunk(ctx, r, chunks,
                   [&](std::uint32_t k, Range c) { left_counts[k] = count_left(in, c, f, best), sizes[k] = c.size(); });
    const ChunkCursors cursors(r, left_counts, sizes);
    std::vector<CentroidBounds> chunk_sides(2 * std::size_t(chunks));
    for_each_chunk(ctx, r, chunks, [&](std::uint32_t k, Range c) {
        ChildBinning mine[2] = {child[0], child[1]};
        for (int s = 0; s < 2; ++s) mine[s].copies = slots[s] >= 0 ? &copies[4 * k + 2 * s] : nullptr;
        partition_and_bin(in, ctx.buffers[1 - src], c, cursors.left[k], cursors.right[k], f, best, mine,
                          sides ? &chunk_sides[2 * k] : nullptr);
    });
    for (int s = 0; s < 2; ++s) {
        for (std::uint32_t k = 0; k < chunks && sides; ++k) sides[s].merge(chunk_sides[2 * k + s]);
        if (slots[s] < 0) continue;
        const BinSet target = store.slot(std::uint32_t(slots[s]));
        target.reset();
        for (std::uint32_t k = 0; k < chunks; ++k)
            target.merge(copies[4 * k + 2 * s]), target.merge(copies[4 * k + 2 * s + 1]);
    }
    return cursors.mid;
}

}  // namespace

std::vector<Bucket> carry_bins(SplitScratch& scratch, std::int32_t slot) {
    if (slot < 0) return {};
    const BinSet from = scratch.bins->slot(std::uint32_t(slot));
    return {from.bucket, from.bucket + 3 * std::size_t(from.bins)};
}

std::int32_t adopt_bins(SplitScratch& scratch, const std::vector<Bucket>& carried) {
    if (carried.empty()) return -1;
    const auto bins = static_cast<std::uint32_t>(carried.size() / 3);
    if (!scratch.bins) scratch.bins = std::make_unique<BinStore>(bins);
    std::copy(carried.begin(), carried.end(), scratch.bins->slot(kCarriedSlot).bucket);
    return std::int32_t(kCarriedSlot);
}

std::optional<Split> split_binned_sah(SplitContext& ctx, Range r, int src, const NodeBounds& b, int axis) {
    const bool by_centroids = ctx.config.bin_bounds == BinBounds::Centroids;
    const BinFrame frame(by_centroids ? b.centroids : b.box, ctx.config.bins);
    const BinSet bins =
        b.bins >= 0 ? store_of(ctx).slot(std::uint32_t(b.bins)) : bin_node(ctx, r, ctx.buffers[src], frame);
    const SahCost sah(ctx.config);
    const BinSplit best =
        best_bin_split(bins, frame, axis == kAllAxes ? 0 : axis, axis == kAllAxes ? 2 : axis, sah, b.box.half_area());
    if (best.axis < 0) return std::nullopt;
    Split s;
    s.cost = best.cost;
    if (ctx.leaf_allowed && sah.leaf(r.size()) <= best.cost) {
        s.leaf = true;
        return s;
    }
    // Before the pass: it may overwrite this node's buckets with its right child's.
    s.left.box = bins.box_of(best.axis, 0, best.last_left + 1);
    s.right.box = bins.box_of(best.axis, best.last_left + 1, frame.bins);
    const std::uint32_t n_left = bins.count_of(best.axis, 0, best.last_left + 1);
    ChildBinning child[2] = {{BinFrame(s.left.box, frame.bins)}, {BinFrame(s.right.box, frame.bins)}};
    // Buckets over centroid bounds: a child's frame is known only after the pass, so it bins itself.
    // Small children are built whole by the small-subtree builder, which needs no buckets.
    const std::uint32_t small = small_subtree_size(ctx.config);
    const std::int32_t slots[2] = {!by_centroids && n_left > small ? std::int32_t(ctx.child_slot + 1) : -1,
                                   !by_centroids && r.size() - n_left > small ? std::int32_t(ctx.child_slot) : -1};
    // The children's centroid bounds are gathered only for the axis policies that read them;
    // otherwise their boxes stand in for them (they contain the centroids; see NodeBounds).
    const bool centroids =
        ctx.config.axis == AxisPolicy::Largest || ctx.config.axis == AxisPolicy::Random || by_centroids;
    CentroidBounds sides[2];
    CentroidBounds* gathered = centroids ? sides : nullptr;
    const std::uint32_t chunks = chunk_count(ctx, r);
    s.mid = chunks_in_turn(ctx, chunks) ? partition_whole(ctx, r, src, frame, best, child, slots, gathered, chunks)
                                        : partition_chunks(ctx, r, src, frame, best, child, slots, gathered, chunks);
    s.left.centroids = centroids ? sides[0].halved() : s.left.box;
    s.right.centroids = centroids ? sides[1].halved() : s.right.box;
    s.left.bins = slots[0], s.right.bins = slots[1];
    s.buffer = static_cast<std::uint8_t>(1 - src);
    return s;
}

}  // namespace bvhlab
