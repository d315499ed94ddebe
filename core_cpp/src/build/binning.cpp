#include "binning.h"
#include "sah_sweep.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "bvhlab/isa.h"

namespace bvhlab {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

}  // namespace

BinFrame::BinFrame(const Aabb& box, std::uint32_t n_bins) : bins(n_bins) {
    // The three axes at once (lane 3: an extent of 0, never binned).
    const F4 lo = F4::set3(box.lo.x, box.lo.y, box.lo.z), extent = F4::set3(box.hi.x, box.hi.y, box.hi.z) - lo;
    const F4 sc = F4::splat(float(n_bins)) / (extent + extent);
    // an infinite extent cannot be binned (its scale is 0)
    const F4 is_binned = less(F4::splat(0.0f), extent) & less(F4::splat(0.0f), sc) & less(sc, F4::splat(kInf));
    origin2 = lo + lo, scale = sc & is_binned;
    origin2.store(origin2_of), scale.store(scale_of);
    const int bits = lane_bits(is_binned);
    for (int a = 0; a < 3; ++a) binned[a] = (bits >> a) & 1;
    top_of = float(n_bins - 1), top = F4::splat(top_of);
}

Bucket Bucket::empty() {
    Bucket b{F4::splat(kInf), F4::splat(kInf)};
    b.set_count(0);
    return b;
}

#if defined(BVHLAB_AVX2_KERNELS)
namespace avx2 {  // binning_avx2.cpp
void reset_buckets(Bucket* bucket, std::size_t n, const Bucket& empty);
void merge_buckets(Bucket* into, const Bucket* other, std::size_t n);
}  // namespace avx2
#endif

void BinSet::reset() const {
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() >= Isa::Avx2) return avx2::reset_buckets(bucket, 3 * std::size_t(bins), Bucket::empty());
#endif
    std::fill(bucket, bucket + 3 * std::size_t(bins), Bucket::empty());
}

void BinSet::merge(const BinSet& other) const {
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() >= Isa::Avx2) return avx2::merge_buckets(bucket, other.bucket, 3 * std::size_t(bins));
#endif
    for (std::size_t i = 0; i < 3 * std::size_t(bins); ++i) {
        Bucket& b = bucket[i];
        const Bucket& o = other.bucket[i];
        const std::uint32_t n = b.count() + o.count();  // the min below keeps one of the two counts, not their sum
        b.lo = min(b.lo, o.lo), b.neg_hi = min(b.neg_hi, o.neg_hi), b.set_count(n);
    }
}

Aabb BinSet::box_of(int axis, std::uint32_t first, std::uint32_t last) const {
    F4 lo = F4::splat(kInf), neg_hi = lo;
    for (std::uint32_t k = first; k < last; ++k) {
        const Bucket& b = bucket[std::size_t(axis) * bins + k];
        lo = min(lo, b.lo), neg_hi = min(neg_hi, b.neg_hi);
    }
    return to_aabb(lo, neg(neg_hi));
}

std::uint32_t BinSet::count_of(int axis, std::uint32_t first, std::uint32_t last) const {
    std::uint32_t n = 0;
    for (std::uint32_t k = first; k < last; ++k) n += bucket[std::size_t(axis) * bins + k].count();
    return n;
}

BinSet BinStore::slot(std::uint32_t s) {
    if (slots_.size() <= s) slots_.resize(s + 1);
    if (!slots_[s])
        // whole cache lines: the chunks of a parallel pass fill their slots on different threads
        slots_[s].reset(static_cast<Bucket*>(std::aligned_alloc(64, (3 * sizeof(Bucket) * bins_ + 63) / 64 * 64)));
    if (!slots_[s]) throw std::bad_alloc();
    return {slots_[s].get(), bins_};
}

PieceCounts& BinStore::pieces(std::uint32_t s) {
    if (pieces_.size() <= s) pieces_.resize(s + 1);
    return pieces_[s];
}

#if defined(BVHLAB_AVX2_KERNELS)
namespace avx2 {  // binning_avx2.cpp
void bin_refs(const PrimRef* refs, Range r, const BinFrame& f, const BinSet copies[2]);
std::uint32_t partition_and_bin(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                                const BinFrame& parent, const BinSplit& split, const ChildBinning child[2],
                                CentroidBounds sides[2]);
}  // namespace avx2
#endif

namespace portable {

void bin_refs(const PrimRef* refs, Range r, const BinFrame& f, const BinSet copies[2]) {
    alignas(16) std::uint32_t k[4];
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        const F4 lo = refs[i].lo4(), hi = refs[i].hi4(), neg_hi = neg(hi);
        f.indices(lo + hi, k);
        const BinSet& b = copies[i & 1];
        b.add(0, k[0], lo, neg_hi), b.add(1, k[1], lo, neg_hi), b.add(2, k[2], lo, neg_hi);
    }
}

}  // namespace portable

void bin_refs(const PrimRef* refs, Range r, const BinFrame& f, const BinSet copies[2]) {
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() >= Isa::Avx2) return avx2::bin_refs(refs, r, f, copies);
#endif
    portable::bin_refs(refs, r, f, copies);
}

BinSplit best_bin_split(const BinSet& bins, const BinFrame& f, int first_axis, int last_axis, const SahCost& sah,
                        float parent_area) {
    // The O(B) sweep per axis (the improvement over the report's O(n + B²), §2.3.2).
    BinSplit best;
    const AxisCuts cuts = cheapest_bin_cuts(bins.bucket, bins.bins, sah, SahCost::inverse_area(parent_area));
    for (int a = first_axis; a <= last_axis; ++a)
        if (f.binned[a] && cuts.cost[a] < best.cost) best = {cuts.cost[a], a, cuts.last_left[a]};  // finite: found
    return best;
}

Aabb CentroidBounds::halved() const {
    const F4 half = F4::splat(0.5f);
    return to_aabb(lo * half, neg(neg_hi) * half);
}

namespace {

/// One copy of one child's buckets, as base pointers per axis.
struct BinTarget {
    Bucket* axis[3];
};
/// What the fused pass needs of one side: the child's frame and its two bucket copies.
struct SideTarget {
    F4 origin2, scale;
    BinTarget copy[2];
    bool binned;
};

SideTarget side_target(const ChildBinning& c) {
    SideTarget t{c.frame.origin2, c.frame.scale, {}, c.copies != nullptr};
    for (int k = 0; k < 2 && t.binned; ++k)
        for (int a = 0; a < 3; ++a) t.copy[k].axis[a] = c.copies[k].bucket + std::size_t(a) * c.copies[k].bins;
    return t;
}

/// Floats in their order as unsigned integers (-inf ... -0, +0 ... +inf ascending), and back.
std::uint32_t order_key(float x) {
    std::uint32_t b;
    std::memcpy(&b, &x, sizeof(b));
    return b >> 31 ? ~b : b | 0x80000000u;
}
float from_order_key(std::uint32_t k) {
    const std::uint32_t b = k >> 31 ? k & 0x7fffffffu : ~k;
    float x;
    std::memcpy(&x, &b, sizeof(x));
    return x;
}

}  // namespace

float right_start(const BinFrame& f, const BinSplit& split) {
    const int a = split.axis;
    // index() is monotone in c2 (each rounding and the clamp are), so the left side is every c2
    // below a threshold: the first float whose bucket is above last_left, found by bisection in
    // float order. The guess, where the unrounded bucket coordinate reaches last_left + 1, is
    // within a few floats of it; the bracket widens until it holds the threshold.
    const auto left = [&](std::uint32_t k) { return f.index(from_order_key(k), a) <= split.last_left; };
    const std::uint32_t guess = order_key(f.origin2_of[a] + (float(split.last_left) + 1.0f) / f.scale_of[a]);
    const std::uint32_t first = order_key(-std::numeric_limits<float>::infinity()),
                        last = order_key(std::numeric_limits<float>::infinity());
    // Most often the threshold is the guess or the float after it: two tests, no search.
    if (guess > first && guess < last) {
        if (left(guess)) {
            if (!left(guess + 1)) return from_order_key(guess + 1);
        } else if (left(guess - 1)) {
            return from_order_key(guess);
        }
    }
    // invariant after widening: left(lo), !left(hi)
    std::uint32_t lo = guess - first > 2 ? guess - 2 : first, hi = last - guess > 2 ? guess + 2 : last;
    for (std::uint32_t step = 4; !(lo == first || left(lo)); step *= 2) lo = lo - first > step ? lo - step : first;
    for (std::uint32_t step = 4; !(hi == last || !left(hi)); step *= 2) hi = last - hi > step ? hi + step : last;
    if (!left(lo)) return from_order_key(first);  // nothing goes left (cannot happen for a split)
    if (left(hi)) return from_order_key(last);    // everything goes left (the same)
    while (hi - lo > 1) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        (left(mid) ? lo : hi) = mid;
    }
    return from_order_key(hi);
}

F4 split_threshold(const BinFrame& f, const BinSplit& split) {
    float v[4];
    for (float& x : v) x = -std::numeric_limits<float>::infinity();
    v[split.axis] = right_start(f, split);
    return F4::load(v);
}

std::uint32_t count_left(const PrimRef* src, Range r, const BinFrame& parent, const BinSplit& split) {
    // The passes send a reference left when any lane of its twice-centroid is below
    // split_threshold(), whose lanes but the split axis's are -inf: the same as this one sum and
    // compare on the axis, which GCC vectorizes (half the instructions of the four-lane test).
    const float t = right_start(parent, split);
    const float* lo = src[r.begin].lo + split.axis;  // hi is 4 floats on, the next reference 8
    const float* const end = lo + 8 * std::size_t(r.size());
    std::uint32_t n[2] = {0, 0};
    for (; lo + 8 < end; lo += 16) n[0] += lo[0] + lo[4] < t ? 1u : 0u, n[1] += lo[8] + lo[12] < t ? 1u : 0u;
    if (lo < end) n[0] += lo[0] + lo[4] < t ? 1u : 0u;
    return n[0] + n[1];
}

namespace portable {

std::uint32_t partition_and_bin(const PrimRef* __restrict src, PrimRef* __restrict dst, Range r, std::uint32_t left,
                                std::uint32_t right, const BinFrame& parent, const BinSplit& split,
                                const ChildBinning child[2], CentroidBounds sides[2]) {
    const SideTarget target[2] = {side_target(child[0]), side_target(child[1])};
    const F4 split_at = split_threshold(parent, split), top = parent.top;
    // Two accumulators per side (even and odd references), so that a run of references going the
    // same way does not chain through one min.
    CentroidBounds acc[2][2];
    alignas(16) std::uint32_t k[4];
    for (std::uint32_t i = r.begin; i < r.end; ++i) {
        const PrimRef& p = src[i];
        const F4 lo = p.lo4(), hi = p.hi4(), c2 = lo + hi, neg_hi = neg(hi);
        const std::uint32_t l = any_lane(less(c2, split_at)) ? 1u : 0u;  // the parent's bucket <= last_left
        const std::uint32_t mask = 0u - l;
        dst[((right - 1) & ~mask) | (left & mask)] = p;
        left += l;
        right -= 1u - l;
        if (sides) {
            CentroidBounds& c = acc[i & 1][1 - l];
            c.lo = min(c.lo, c2), c.neg_hi = min(c.neg_hi, neg(c2));
        }
        const SideTarget& t = target[1 - l];
        if (!t.binned) continue;
        // The child's box holds the reference's, so c2 - origin2 >= 0: only the top needs a clamp.
        truncate_to_u32(min((c2 - t.origin2) * t.scale, top), k);
        const BinTarget& b = t.copy[i & 1];
        for (int a = 0; a < 3; ++a) b.axis[a][k[a]].add(lo, neg_hi);
    }
    for (int s = 0; s < 2 && sides; ++s) sides[s].merge(acc[0][s]), sides[s].merge(acc[1][s]);
    return left;
}

}  // namespace portable

std::uint32_t partition_and_bin(const PrimRef* src, PrimRef* dst, Range r, std::uint32_t left, std::uint32_t right,
                                const BinFrame& parent, const BinSplit& split, const ChildBinning child[2],
                                CentroidBounds sides[2]) {
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() >= Isa::Avx2)
        return avx2::partition_and_bin(src, dst, r, left, right, parent, split, child, sides);
#endif
    return portable::partition_and_bin(src, dst, r, left, right, parent, split, child, sides);
}

}  // namespace bvhlab
