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

// The sort moves 8-byte (code, index) keys, not the 32-byte references: three passes of 10
// bits, whose three histograms are counted in the one pass that makes the codes; the references
// are then gathered once in sorted order (Embree's Morton builder sorts such pairs too).
void sort_by_morton_code(BigVector<PrimRef>& refs, const Aabb& centroid_bounds) {
    Vec3 extent = centroid_bounds.extent();
    float scale[3];
    for (int a = 0; a < 3; ++a) {  // a subnormal extent would make the scale inf, and 0·inf = NaN
        const float s = 1024.0f / extent[a];
        scale[a] = extent[a] > 0 && std::isfinite(s) ? s : 0.0f;
    }
    const std::size_t n = refs.size();
    struct Key {
        std::uint32_t code, index;
    };
    BigVector<Key> keys(n), tmp(n);
    std::vector<std::array<std::size_t, 1024>> start(3);
    for (auto& digit : start) digit.fill(0);
    for (std::size_t i = 0; i < n; ++i) {
        std::uint32_t q[3];
        for (int a = 0; a < 3; ++a) q[a] = quantize(refs[i].centroid(a), centroid_bounds.lo[a], scale[a]);
        const std::uint32_t code = spread_bits(q[0]) << 2 | spread_bits(q[1]) << 1 | spread_bits(q[2]);
        keys[i] = {code, static_cast<std::uint32_t>(i)};
        for (int d = 0; d < 3; ++d) ++start[d][(code >> (10 * d)) & 1023u];
    }
    for (int d = 0; d < 3; ++d) {
        std::size_t sum = 0;
        bool one_bucket = false;
        for (std::size_t& c : start[d]) one_bucket |= c == n, sum += c, c = sum - c;  // exclusive prefix sum
        if (one_bucket) continue;  // this digit is the same in every code: the pass would not move a key
        for (const Key& k : keys) tmp[start[d][(k.code >> (10 * d)) & 1023u]++] = k;
        keys.swap(tmp);
    }
    // The gather reads the references at random: fetch the one kAhead keys later meanwhile.
    constexpr std::size_t kAhead = 16;
    BigVector<PrimRef> sorted(n);
    for (std::size_t j = 0; j < n; ++j) {
        if (j + kAhead < n) __builtin_prefetch(&refs[keys[j + kAhead].index]);
        sorted[j] = refs[keys[j].index];
        sorted[j].code = keys[j].code;
    }
    refs.swap(sorted);
}

}  // namespace bvhlab
