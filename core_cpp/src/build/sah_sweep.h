// sah_sweep.h — the cheapest cut of a sequence of boxes (report §2.3.2): the buckets of the
// binned SAH (small ranges sweep their sorted primitives in small_subtree.cpp instead). One
// suffix and one prefix pass of box unions, then the areas and costs of the candidates four at
// a time.
#pragma once
#include <cstdint>
#include <limits>

#include "bvhlab/prim_ref.h"
#include "bvhlab/sah.h"

namespace bvhlab {

/// The best cut: elements [0, last_left] on the left. `found` is false when no cut leaves both
/// sides non-empty.
struct Cut {
    float cost = std::numeric_limits<float>::infinity();
    std::uint32_t last_left = 0;
    bool found = false;
};

/// A sequence of n boxes (n <= kMaxBins) as (lo, -hi): element j at lo[j * stride] and
/// neg_hi[j * stride]; count[j] primitives each (1 each when count is null).
struct BoxSequence {
    const F4* lo;
    const F4* neg_hi;
    std::size_t stride;
    const std::uint32_t* count;
    std::uint32_t n;
};

/// Prefix and suffix unions of a sequence of at most kCapacity boxes: candidate c has
/// left = [0, c], right = [c + 1, n); hi is stored as it is (not negated).
template <std::uint32_t kCapacity>
struct Unions {
    F4 left_lo[kCapacity], left_hi[kCapacity], right_lo[kCapacity], right_hi[kCapacity];
    std::uint32_t left_n[kCapacity], right_n[kCapacity];
    void fill(const BoxSequence& s);
};

/// Every boundary is a candidate; a strictly cheaper one replaces the best so far, so ties go
/// to the first. Costs are SahCost::split's, bit for bit. `u` (capacity >= seq.n + 3) is
/// filled on the way: the unions of the chosen cut are u.left_*[last_left], u.right_*[last_left].
template <std::uint32_t kCapacity>
Cut cheapest_cut(const BoxSequence& seq, const SahCost& sah, float inv_parent_area, Unions<kCapacity>& u);

}  // namespace bvhlab
