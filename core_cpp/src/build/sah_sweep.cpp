#include "sah_sweep.h"

#include "bvhlab/split.h"

namespace bvhlab {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

}  // namespace

namespace {

/// Prefix and suffix unions with the element layout known at compile time (bins: stride 2 and
/// counts; sorted primitives: stride 1, one each).
template <std::uint32_t kStride, bool kCounted, std::uint32_t kCapacity>
void fill_unions(const BoxSequence& s, Unions<kCapacity>& u) {
    F4 lo = F4::splat(kInf), neg_hi = lo;
    std::uint32_t n = 0;
    for (std::uint32_t j = s.n - 1; j > 0; --j) {  // right of candidate j - 1
        lo = min(lo, s.lo[j * kStride]), neg_hi = min(neg_hi, s.neg_hi[j * kStride]);
        n += kCounted ? s.count[j] : 1u;
        u.right_lo[j - 1] = lo, u.right_hi[j - 1] = neg(neg_hi), u.right_n[j - 1] = n;
    }
    lo = F4::splat(kInf), neg_hi = lo, n = 0;
    for (std::uint32_t j = 0; j + 1 < s.n; ++j) {
        lo = min(lo, s.lo[j * kStride]), neg_hi = min(neg_hi, s.neg_hi[j * kStride]);
        n += kCounted ? s.count[j] : 1u;
        u.left_lo[j] = lo, u.left_hi[j] = neg(neg_hi), u.left_n[j] = n;
    }
    // pad the candidates to a multiple of four with copies of the last (never chosen: not cheaper)
    for (std::uint32_t c = s.n - 1; c % 4 != 0; ++c) {
        u.left_lo[c] = u.left_lo[c - 1], u.left_hi[c] = u.left_hi[c - 1], u.left_n[c] = u.left_n[c - 1];
        u.right_lo[c] = u.right_lo[c - 1], u.right_hi[c] = u.right_hi[c - 1], u.right_n[c] = u.right_n[c - 1];
    }
}

}  // namespace

template <std::uint32_t kCapacity>
void Unions<kCapacity>::fill(const BoxSequence& s) {
    if (s.count && s.stride == 2) fill_unions<2, true>(s, *this);
    else if (!s.count && s.stride == 1) fill_unions<1, false>(s, *this);
    else if (s.count) fill_unions<1, true>(s, *this);  // (unused layouts: correct, not specialised)
    else fill_unions<1, false>(s, *this);
}

namespace {

/// SahCost::split of four candidates at once (the same operations lane by lane).
template <class U>
F4 split_costs(const U& u, std::uint32_t c, const SahCost& sah, float inv_parent) {
    const F4 nl = F4::from_counts(u.left_n + c), nr = F4::from_counts(u.right_n + c);
    F4 ratio;
    if (inv_parent > 0.0f) {
        ratio = (half_areas(u.left_lo + c, u.left_hi + c) * nl + half_areas(u.right_lo + c, u.right_hi + c) * nr) *
                F4::splat(inv_parent);
    } else {
        std::uint32_t total[4];
        for (int k = 0; k < 4; ++k) total[k] = u.left_n[c + k] + u.right_n[c + k];
        ratio = F4::from_counts(total);
    }
    return F4::splat(sah.traversal) + ratio * F4::splat(sah.intersection);
}

}  // namespace

template <std::uint32_t kCapacity>
Cut cheapest_cut(const BoxSequence& seq, const SahCost& sah, float inv_parent_area, Unions<kCapacity>& u) {
    Cut best;
    if (seq.n < 2) return best;
    u.fill(seq);
    const std::uint32_t candidates = seq.n - 1;
    alignas(16) float cost[4];
    for (std::uint32_t c = 0; c < candidates; c += 4) {
        split_costs(u, c, sah, inv_parent_area).store(cost);
        for (std::uint32_t k = 0; k < 4 && c + k < candidates; ++k) {
            if (u.left_n[c + k] == 0 || u.right_n[c + k] == 0 || !(cost[k] < best.cost)) continue;
            best = {cost[k], c + k, true};
        }
    }
    return best;
}

template struct Unions<kMaxBins + 3>;
template Cut cheapest_cut(const BoxSequence&, const SahCost&, float, Unions<kMaxBins + 3>&);

}  // namespace bvhlab
