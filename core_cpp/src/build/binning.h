// binning.h — the passes of the binned SAH (report §2.3.2, PBRT §4.3.2; Wald 2007): every
// reference falls into one of B equal buckets per axis of its node's box; an O(B) sweep per axis
// finds the cheapest bucket boundary; one pass then scatters the references by bucket and, in
// the same pass, drops each into its child's buckets (so every level of the tree costs one pass
// over the references, not two). Buckets span the node's box rather than its centroids'
// (tinybvh does the same): the children's boxes, known from the buckets before the pass, are
// then their frames; on Crytek Sponza the trees are as good or better (SAH 70.4 vs 72.6 at 12
// buckets, 8 per leaf, all axes).
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "bvhlab/split.h"

namespace bvhlab {

/// Where the buckets of one node lie: bucket k of an axis holds the references whose twice-
/// centroid c2 has k = trunc((c2 - origin2) · scale), clamped to [0, B - 1]. Binning uses
/// indices(); the passes that split a node send a reference left by split_threshold(), whose
/// threshold is found with index(), so all agree on every reference.
struct BinFrame {
    F4 origin2;  ///< twice the box minimum (lane 3: 0)
    F4 scale;    ///< B / (2 · box extent) per axis; 0 for a flat axis
    F4 top;      ///< B - 1 in every lane
    float origin2_of[4] = {0, 0, 0, 0}, scale_of[4] = {0, 0, 0, 0}, top_of = 0;  ///< the same, for index()
    bool binned[3] = {false, false, false};  ///< the axes with an extent (the others are one bucket)
    std::uint32_t bins = 0;

    BinFrame() = default;
    BinFrame(const Aabb& box, std::uint32_t bins);

    /// Buckets of all three axes from twice the centroid (lanes 0-2). NaN goes to bucket 0, and
    /// values clamp before they are converted, so the conversion is always defined.
    void indices(F4 c2, std::uint32_t out[4]) const {
        F4 x = (c2 - origin2) * scale;
        truncate_to_u32(min(max(x, F4::splat(0.0f)), top), out);
    }
    /// The bucket of twice-centroid c2 on one axis: the scalar twin of indices().
    std::uint32_t index(float c2, int axis) const {
        float x = (c2 - origin2_of[axis]) * scale_of[axis];
        x = x > 0.0f ? x : 0.0f;  // max(x, 0) in indices(): NaN → 0
        return static_cast<std::uint32_t>(x < top_of ? x : top_of);
    }
};

/// One bucket of one axis in 32 bytes: the box of its references as (lo, -hi), so that one `min`
/// grows both, and their count in lo's lane 3 as the bits of an integer plus kCountBias. Those bits
/// are a positive normal float while a copy counts fewer than 2^30 references (a pass alternates
/// two copies; a build has fewer than 2^31), so the `min` with a reference's box, whose lane 3 is
/// +inf, keeps them (also with denormals flushed); an integer add of 1 in lane 3 counts. A merged
/// set (BinSet::merge) may count up to 2^31, past the normal floats: it is only read (count()),
/// never binned into, as every pass resets its copies first.
struct alignas(32) Bucket {
    static constexpr std::uint32_t kCountBias = 0x00800000u;  ///< the bits of the least normal float
    F4 lo, neg_hi;

    static Bucket empty();
    std::uint32_t count() const {
        std::uint32_t bits;
        std::memcpy(&bits, reinterpret_cast<const char*>(&lo) + 12, sizeof(bits));
        return bits - kCountBias;
    }
    void set_count(std::uint32_t n) {
        const std::uint32_t bits = n + kCountBias;
        std::memcpy(reinterpret_cast<char*>(&lo) + 12, &bits, sizeof(bits));
    }
    /// Grows the box by a reference's (lo, -hi) and counts it: the count is read before the `min`
    /// and written after, so the reference's lane 3 need not be +inf on the portable paths.
    void add(F4 ref_lo, F4 ref_neg_hi) {
        const std::uint32_t n = count() + 1;
        lo = min(lo, ref_lo), neg_hi = min(neg_hi, ref_neg_hi), set_count(n);
    }
};
static_assert(sizeof(Bucket) == 32 && offsetof(Bucket, neg_hi) == 16,
              "binning_avx2.cpp reads the box as 32 bytes at 0 and the count in lane 3");

/// The buckets of the three axes of one node (a view into a BinStore slot).
struct BinSet {
    Bucket* bucket = nullptr;  ///< [a B + k]: bucket k of axis a
    std::uint32_t bins = 0;

    void reset() const;
    void merge(const BinSet& other) const;
    void add(int axis, std::uint32_t k, F4 lo, F4 neg_hi) const {
        bucket[std::size_t(axis) * bins + k].add(lo, neg_hi);
    }
    /// The union of buckets [first, last) of `axis`, and how many references they hold.
    Aabb box_of(int axis, std::uint32_t first, std::uint32_t last) const;
    std::uint32_t count_of(int axis, std::uint32_t first, std::uint32_t last) const;
};

/// A slot's buckets counted piece by piece, where a pass in chunks on the pool filled them: the
/// pass's chunk k wrote piece k of the range (the range is the pieces one after another, in
/// order) and counted it in buckets of its own. A chunked pass over the range then cuts it at
/// piece boundaries and knows how many references of each chunk go left from these counts, so
/// it needs no counting pass before it (two threads, room1m: that pass took 8 of the 33 ms spent
/// above the deferred ranges). `range` says which range they describe (empty: none).
struct PieceCounts {
    Range range;
    std::vector<std::uint32_t> sizes;   ///< references per piece
    std::vector<std::uint32_t> counts;  ///< [p · 3B + a · B + k]: piece p's references in bucket k of axis a
};

/// Bucket memory of one thread: slot s (allocated on first use) holds one BinSet, and the
/// PieceCounts of its buckets where a chunked pass filled them.
class BinStore {
public:
    explicit BinStore(std::uint32_t bins) : bins_(bins) {}
    std::uint32_t bins() const { return bins_; }
    BinSet slot(std::uint32_t s);
    PieceCounts& pieces(std::uint32_t s);

private:
    struct Free {
        void operator()(Bucket* p) const { std::free(p); }
    };
    std::uint32_t bins_;
    std::vector<std::unique_ptr<Bucket, Free>> slots_;  ///< 3B buckets each
    std::vector<PieceCounts> pieces_;
};

/// The buckets of BinStore slot `slot` of this thread's scratch (NodeBounds::bins), copied out
/// for a range deferred to another thread; empty when `slot` is -1 (nothing binned).
std::vector<Bucket> carry_bins(SplitScratch& scratch, std::int32_t slot);
/// Puts carried buckets into this thread's store, where the range's node will find them: the
/// slot for NodeBounds::bins, or -1 when none were carried (the node then bins itself).
std::int32_t adopt_bins(SplitScratch& scratch, const std::vector<Bucket>& carried);

/// Slots of a BinStore: below kStackSlots, the buckets of the work item at that stack position;
/// then one for a node binned on its own, one for the buckets a deferred range carried here
/// (adopt_bins); then four per chunk of a parallel pass.
inline constexpr std::uint32_t kStackSlots = 2 * gpu::MAX_TREE_HEIGHT + 2;
inline constexpr std::uint32_t kOwnSlot = kStackSlots;
inline constexpr std::uint32_t kCarriedSlot = kStackSlots + 1;
inline constexpr std::uint32_t kChunkSlots = kStackSlots + 2;

/// Adds the references of r to two copies of buckets (reset by the caller): consecutive
/// references alternate between them, so that runs in one bucket do not wait on each other's
/// stores. Merge the second into the first afterwards.
void bin_refs(const PrimRef* refs, Range r, const BinFrame& f, const BinSet copies[2]);

/// The cheapest boundary: buckets [0, last_left] go left on `axis`.
struct BinSplit {
    float cost = std::numeric_limits<float>::infinity();
    int axis = -1;
    std::uint32_t last_left = 0;
};
/// Sweeps the axes in [first_axis, last_axis] that have an extent.
BinSplit best_bin_split(const BinSet& bins, const BinFrame& f, int first_axis, int last_axis, const SahCost& sah,
                        float parent_area);

/// Where the right side of `split` starts on its axis: the smallest twice-centroid c2 whose
/// bucket is above split.last_left. A reference goes left exactly when its c2 on the axis is
/// below it, so the passes compare once per reference instead of computing its bucket.
float right_start(const BinFrame& f, const BinSplit& split);
/// right_start() in the split axis's lane, -inf in the others: a reference goes left exactly
/// when any lane of its twice-centroid (lane 3: 0) is below it.
F4 split_threshold(const BinFrame& f, const BinSplit& split);

/// Twice the centroid bounds of references, as (minimum, minimum of the negated maximum).
struct CentroidBounds {
    F4 lo = F4::splat(std::numeric_limits<float>::infinity()), neg_hi = lo;
    void merge(const CentroidBounds& o) { lo = min(lo, o.lo), neg_hi = min(neg_hi, o.neg_hi); }
    Aabb halved() const;
};

/// One child in the fused pass: its frame and two copies of its buckets (null: not binned). The
/// frame spans a box that holds every reference of the child (its box from the parent's buckets):
/// the pass clamps bucket coordinates only at the top.
struct ChildBinning {
    BinFrame frame;
    const BinSet* copies = nullptr;
};

/// The fused pass: scatters src[r] into dst by the parent's bucket on split.axis (buckets
/// <= last_left forward from `left`, the others backward from `right`, as scatter() in
/// partition.h), drops each reference into its child's buckets and gathers each side's centroid
/// bounds (sides[0] left, sides[1] right; null: not gathered). Returns the left cursor after.
/// Each reference is stored once, at its slot (scatter()'s contained mode), so the chunks of one
/// range may run at once.
std::uint32_t partition_and_bin(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                                const BinFrame& parent, const BinSplit& split, const ChildBinning child[2],
                                CentroidBounds sides[2]);

/// How many references of r go left: the counting pass before a chunked partition_and_bin, for
/// the chunks whose count the pieces do not give (PieceCounts).
std::uint32_t count_left(const PrimRef* src, Range r, const BinFrame& parent, const BinSplit& split);

}  // namespace bvhlab
