// Binned SAH (report §2.3.2, PBRT §4.3.2): B equal buckets per axis, the cheapest bucket
// boundary by an O(B) sweep (the improvement the report names over its O(n + B²) loop), then one
// pass that scatters by bucket and fills the children's buckets (binning.h). At the top of the
// tree the passes run in chunks on every thread.
#include <algorithm>
#include <stdexcept>

#include "binning.h"
#include "partition.h"

namespace bvhlab {
namespace {

BinStore& store_of(SplitContext& ctx) {
    if (!ctx.scratch.bins) ctx.scratch.bins = std::make_unique<BinStore>(ctx.config.bins);
    return *ctx.scratch.bins;
}

/// Records `into` as the pieces of `range`: piece p holds sizes[p] references, counted in the
/// two bucket copies copies_of(p) points at.
template <class CopiesOf>
void record_pieces(PieceCounts& into, Range range, const std::vector<std::uint32_t>& sizes, std::uint32_t bins,
                   const CopiesOf& copies_of) {
    const std::size_t per_piece = 3 * std::size_t(bins);
    into.range = range, into.sizes = sizes;
    into.counts.resize(sizes.size() * per_piece);
    for (std::size_t p = 0; p < sizes.size(); ++p) {
        const BinSet* copies = copies_of(p);
        for (std::size_t i = 0; i < per_piece; ++i)
            into.counts[p * per_piece + i] = copies[0].bucket[i].count() + copies[1].bucket[i].count();
    }
}

/// The buckets of a node its parent did not bin: one pass of its own (in chunks at the top,
/// whose counts are kept as the pieces of the node's slot).
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
    PieceCounts& pieces = store.pieces(kOwnSlot);
    pieces.range = {};
    if (!chunks_in_turn(ctx, chunks)) {
        std::vector<std::uint32_t> sizes(chunks);
        for (std::uint32_t k = 0; k < chunks; ++k) sizes[k] = chunk_of(r, k, chunks).size();
        std::vector<BinSet> copies(2 * std::size_t(chunks));
        for (std::uint32_t k = 0; k < 2 * chunks; ++k) copies[k] = store.slot(kChunkSlots + k);
        record_pieces(pieces, r, sizes, f.bins, [&](std::size_t p) { return &copies[2 * p]; });
    }
    return own;
}

/// The chunks of a pass on the pool over r, and how many references of each go left.
struct ChunkPlan {
    std::vector<Range> chunks;
    std::vector<std::uint32_t> left_counts, sizes;
    void add(Range c, std::uint32_t left) {
        chunks.push_back(c), left_counts.push_back(left), sizes.push_back(c.size());
    }
};

/// Finds the left counts of plan.chunks[i] for each i in `which` by a counting pass over them.
void count_chunks(SplitContext& ctx, ChunkPlan& plan, const std::vector<std::uint32_t>& which, const PrimRef* in,
                  const BinFrame& f, const BinSplit& best) {
    std::vector<Range> ranges(which.size());
    for (std::size_t i = 0; i < which.size(); ++i) ranges[i] = plan.chunks[which[i]];
    for_each_range(ctx, ranges,
                   [&](std::uint32_t i, Range c) { plan.left_counts[which[i]] = count_left(in, c, f, best); });
}

/// Equal chunks of r and a counting pass over them.
ChunkPlan plan_by_counting(SplitContext& ctx, Range r, const PrimRef* in, const BinFrame& f, const BinSplit& best,
                           std::uint32_t chunks) {
    ChunkPlan plan;
    std::vector<std::uint32_t> all(chunks);
    for (std::uint32_t k = 0; k < chunks; ++k) plan.add(chunk_of(r, k, chunks), 0), all[k] = k;
    count_chunks(ctx, plan, all, in, f, best);
    return plan;
}

/// About `chunks` chunks of r cut at the boundaries of its pieces, each one's left count summed
/// from the pieces' buckets at `best`, with no pass over the references: consecutive small pieces
/// make one chunk. A piece too large for the threads to share the pass evenly (more than a
/// (2 · threads)-th of r: none with two threads and even splits, as pieces are no larger than the
/// chunks of the pass before) is cut into chunks of its own, and all but its last counted.
ChunkPlan plan_from_pieces(SplitContext& ctx, const PieceCounts& pieces, Range r, const PrimRef* in, const BinFrame& f,
                           const BinSplit& best, std::uint32_t chunks) {
    const std::uint32_t target = std::max<std::uint32_t>(1, r.size() / chunks);
    const std::uint32_t largest = std::max(target, r.size() / (2 * std::max(1u, ctx.parallel->threads)));
    const std::size_t per_piece = 3 * std::size_t(f.bins);
    struct Cut {
        std::uint32_t first, parts, left;  // chunks [first, first + parts) of one piece with `left` going left
    };
    std::vector<Cut> cuts;
    std::vector<std::uint32_t> counted;
    ChunkPlan plan;
    std::uint32_t begin = r.begin, size = 0, left = 0;
    const auto close = [&] {
        if (size > 0) plan.add({begin, begin + size}, left);
        begin += size, size = left = 0;
    };
    for (std::size_t p = 0; p < pieces.sizes.size(); ++p) {
        const std::uint32_t* count = &pieces.counts[p * per_piece + std::size_t(best.axis) * f.bins];
        std::uint32_t piece_left = 0;
        for (std::uint32_t k = 0; k <= best.last_left; ++k) piece_left += count[k];
        if (pieces.sizes[p] > largest) {
            close();
            const Range piece{begin, begin + pieces.sizes[p]};
            const std::uint32_t parts = (piece.size() + target - 1) / target;
            cuts.push_back({std::uint32_t(plan.chunks.size()), parts, piece_left});
            for (std::uint32_t j = 0; j < parts; ++j) {
                if (j + 1 < parts) counted.push_back(std::uint32_t(plan.chunks.size()));
                plan.add(chunk_of(piece, j, parts), 0);
            }
            begin = piece.end;
            continue;
        }
        size += pieces.sizes[p], left += piece_left;
        if (size >= target) close();
    }
    close();
    if (counted.empty()) return plan;
    count_chunks(ctx, plan, counted, in, f, best);
    for (const Cut& cut : cuts) {
        std::uint32_t rest = cut.left;  // what the piece's last chunk sends left; wraps if the counts disagree,
        for (std::uint32_t j = 0; j + 1 < cut.parts; ++j) rest -= plan.left_counts[cut.first + j];
        plan.left_counts[cut.first + cut.parts - 1] = rest;  // which partition_chunks' check then catches
    }
    return plan;
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
    for (int s = 0; s < 2; ++s) {
        if (slots[s] < 0) continue;
        copies[s][0].merge(copies[s][1]);
        store.pieces(std::uint32_t(slots[s])).range = {};  // counted as a whole
    }
    return mid;
}

/// The fused pass in chunks on the pool (the top of the tree). Where each chunk writes comes from
/// the counts of r's pieces when its buckets were filled in chunks (the pass before), else from a
/// counting pass. Each chunk fills buckets of its own: merged into the children's slots after,
/// and kept as the children's pieces.
std::uint32_t partition_chunks(SplitContext& ctx, Range r, int src, std::uint32_t own_slot, std::uint32_t n_left,
                               const BinFrame& f, const BinSplit& best, const ChildBinning child[2],
                               const std::int32_t slots[2], CentroidBounds sides[2], std::uint32_t chunks) {
    BinStore& store = store_of(ctx);
    const PrimRef* in = ctx.buffers[src];
    const PieceCounts& pieces = store.pieces(own_slot);  // not used after the plan: recording may move it
    const ChunkPlan plan = pieces.range.begin == r.begin && pieces.range.end == r.end
                               ? plan_from_pieces(ctx, pieces, r, in, f, best, chunks)
                               : plan_by_counting(ctx, r, in, f, best, chunks);
    const auto n = static_cast<std::uint32_t>(plan.chunks.size());
    // The chunks write where their counts say: chunks that miss references, or counts that
    // disagree with the node's buckets (which binning and the partition agree on, reference by
    // reference), would leave slots unwritten, so they stop the build instead.
    std::uint64_t left = 0, total = 0;
    bool fits = true;
    for (std::uint32_t k = 0; k < n; ++k)
        left += plan.left_counts[k], total += plan.sizes[k], fits = fits && plan.left_counts[k] <= plan.sizes[k];
    if (!fits || left != n_left || total != r.size())
        throw std::logic_error("bvhlab: a chunked pass's chunks or counts disagree with its node");
    std::vector<BinSet> copies(4 * std::size_t(n));  // per chunk: left ×2, right ×2
    for (std::uint32_t k = 0; k < 4 * n; ++k)
        if (slots[(k / 2) % 2] >= 0) (copies[k] = store.slot(kChunkSlots + k)).reset();
    const ChunkCursors cursors(r, plan.left_counts, plan.sizes);
    std::vector<CentroidBounds> chunk_sides(2 * std::size_t(n));
    for_each_range(ctx, plan.chunks, [&](std::uint32_t k, Range c) {
        ChildBinning mine[2] = {child[0], child[1]};
        for (int s = 0; s < 2; ++s) mine[s].copies = slots[s] >= 0 ? &copies[4 * k + 2 * s] : nullptr;
        partition_and_bin(in, ctx.buffers[1 - src], c, cursors.left[k], cursors.right[k], f, best, mine,
                          sides ? &chunk_sides[2 * k] : nullptr);
    });
    for (int s = 0; s < 2; ++s) {
        for (std::uint32_t k = 0; k < n && sides; ++k) sides[s].merge(chunk_sides[2 * k + s]);
        if (slots[s] < 0) continue;
        const BinSet target = store.slot(std::uint32_t(slots[s]));
        target.reset();
        for (std::uint32_t k = 0; k < n; ++k)
            target.merge(copies[4 * k + 2 * s]), target.merge(copies[4 * k + 2 * s + 1]);
        // The left side is chunk 0's part first; the right side is written backward from the end,
        // so there chunk 0's part comes last.
        const auto chunk_of_piece = [&](std::size_t p) { return s == 0 ? p : n - 1 - p; };
        std::vector<std::uint32_t> sizes(n);
        for (std::uint32_t p = 0; p < n; ++p) {
            const std::size_t k = chunk_of_piece(p);
            sizes[p] = s == 0 ? plan.left_counts[k] : plan.sizes[k] - plan.left_counts[k];
        }
        const Range side = s == 0 ? Range{r.begin, cursors.mid} : Range{cursors.mid, r.end};
        record_pieces(store.pieces(std::uint32_t(slots[s])), side, sizes, f.bins,
                      [&](std::size_t p) { return &copies[4 * chunk_of_piece(p) + 2 * std::size_t(s)]; });
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
    const std::uint32_t own_slot = b.bins >= 0 ? std::uint32_t(b.bins) : kOwnSlot;  // where `bins` came from
    s.mid = chunks_in_turn(ctx, chunks)
                ? partition_whole(ctx, r, src, frame, best, child, slots, gathered, chunks)
                : partition_chunks(ctx, r, src, own_slot, n_left, frame, best, child, slots, gathered, chunks);
    s.left.centroids = centroids ? sides[0].halved() : s.left.box;
    s.right.centroids = centroids ? sides[1].halved() : s.right.box;
    s.left.bins = slots[0], s.right.bins = slots[1];
    s.buffer = static_cast<std::uint8_t>(1 - src);
    return s;
}

}  // namespace bvhlab
