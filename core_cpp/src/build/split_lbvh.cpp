// LBVH (report §5.2, Karras 2012 / PBRT's HLBVH): the builder sorts the references by the Morton
// code of their centroid once (see morton.cpp); a node then splits where the highest bit that
// differs between its first and last code flips — in place, nothing moves. No axis policy.
#include <algorithm>
#include <bit>

#include "bvhlab/split.h"

namespace bvhlab {

std::optional<Split> split_lbvh(SplitContext& ctx, Range r, int src, const NodeBounds&, int /*axis*/) {
    const PrimRef* refs = ctx.buffers[src];
    std::uint32_t first = refs[r.begin].code, last = refs[r.end - 1].code;
    if (first == last) return std::nullopt;  // equal codes: the builder splits them evenly
    std::uint32_t bit = 1u << (31 - std::countl_zero(first ^ last));
    const PrimRef* mid =
        std::partition_point(refs + r.begin, refs + r.end, [bit](const PrimRef& p) { return (p.code & bit) == 0; });
    Split s;  // the bounds stay empty: the builder makes LBVH boxes from the leaves up
    s.mid = static_cast<std::uint32_t>(mid - refs);
    s.buffer = static_cast<std::uint8_t>(src);
    return s;
}

}  // namespace bvhlab
