#include "morton.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace bvhlab {
namespace {

/// Spreads the low 10 bits of v so that two zero bits follow each (PBRT's LeftShift3).
std::uint32_t spread_bits(std::uint32_t v) {
    v = (v | (v << 16)) & 0x030000FFu;
    v = (v | (v << 8)) & 0x0300F00Fu;
    v = (v | (v << 4)) & 0x030C30C3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
}

std::uint32_t quantize(float x, float lo, float scale) { return truncate_clamped((x - lo) * scale, 1023.0f); }

}  // namespace

void sort_by_morton_code(BigVector<PrimRef>& refs, const Aabb& centroid_bounds) {
    Vec3 extent = centroid_bounds.extent();
    float scale[3];
    for (int a = 0; a < 3; ++a) {  // a subnormal extent would make the scale inf, and 0·inf = NaN
        const float s = 1024.0f / extent[a];
        scale[a] = extent[a] > 0 && std::isfinite(s) ? s : 0.0f;
    }
    for (PrimRef& p : refs) {
        std::uint32_t q[3];
        for (int a = 0; a < 3; ++a) q[a] = quantize(p.centroid(a), centroid_bounds.lo[a], scale[a]);
        p.code = spread_bits(q[0]) << 2 | spread_bits(q[1]) << 1 | spread_bits(q[2]);
    }
    // Three passes of 10 bits cover the 30-bit codes.
    BigVector<PrimRef> tmp(refs.size());
    for (int shift = 0; shift < 30; shift += 10) {
        std::array<std::size_t, 1025> start{};
        for (const PrimRef& p : refs) ++start[((p.code >> shift) & 1023u) + 1];
        for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
        for (const PrimRef& p : refs) tmp[start[(p.code >> shift) & 1023u]++] = p;
        refs.swap(tmp);
    }
}

}  // namespace bvhlab
