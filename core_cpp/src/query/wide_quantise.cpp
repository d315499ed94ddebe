// The quantised wide node (wide_bvh.h WideQNode): its planes rounded outward to 8 bits relative
// to the node's box (Ylitie, Karras and Laine 2017, §3.2; Embree's quantised nodes). The kernels
// decode a plane by the same two operations as decode_plane (wide_traverse.inl plane_of), so a
// decoded box is the same float box on every path.
#include <cmath>
#include <cstring>
#include <limits>

#include "bvhlab/wide_bvh.h"

namespace bvhlab {

float decode_plane(std::uint8_t q, float scale, float origin) {
    const float product = float(q) * scale;  // exact: q < 2^8, scale a power of two ≥ 2^-126
    return product + origin;
}

namespace {

/// The least power of two s ≥ 2^-126 with 255·s ≥ extent (exactly, in double) and
/// decode_plane(255, s, origin) ≥ high: a slot can reach the union's high corner.
float scale_for(float origin, float high) {
    const double extent = double(high) - double(origin);
    int e = -126;
    if (extent > 0.0) e = std::max(e, std::ilogb(extent / 255.0));
    float s = std::ldexp(1.0f, e);
    while (double(s) * 255.0 < extent) s *= 2.0f;
    while (decode_plane(255, s, origin) < high && s < 0x1p126f) s *= 2.0f;  // rounding ties: not expected
    return s;
}

/// The largest q with decode_plane(q) ≤ lo (decode_plane(0) = origin ≤ lo).
std::uint8_t quantise_low(float lo, float scale, float origin) {
    double guess = std::floor((double(lo) - double(origin)) / double(scale));
    int q = guess < 0.0 ? 0 : guess > 255.0 ? 255 : int(guess);
    while (q > 0 && decode_plane(std::uint8_t(q), scale, origin) > lo) --q;
    while (q < 255 && decode_plane(std::uint8_t(q + 1), scale, origin) <= lo) ++q;
    return std::uint8_t(q);
}

/// The least q with decode_plane(q) ≥ hi (decode_plane(255) ≥ the union's high corner ≥ hi).
std::uint8_t quantise_high(float hi, float scale, float origin) {
    double guess = std::ceil((double(hi) - double(origin)) / double(scale));
    int q = guess < 0.0 ? 0 : guess > 255.0 ? 255 : int(guess);
    while (q < 255 && decode_plane(std::uint8_t(q), scale, origin) < hi) ++q;
    while (q > 0 && decode_plane(std::uint8_t(q - 1), scale, origin) >= hi) --q;
    return std::uint8_t(q);
}

}  // namespace

void quantise_node(const WideNode& node, WideQNode& out) {
    std::memset(&out, 0, sizeof out);
    const float* planes = node.lo_x;  // lo_x, hi_x, lo_y, hi_y, lo_z, hi_z: 8 floats each
    for (int k = 0; k < 8; ++k)
        if (node.lo_x[k] <= node.hi_x[k] && node.lo_y[k] <= node.hi_y[k] && node.lo_z[k] <= node.hi_z[k])
            out.used |= 1u << k;
    for (int a = 0; a < 3; ++a) {
        const float* lo = planes + 16 * a;
        const float* hi = lo + 8;
        float low = std::numeric_limits<float>::infinity(), high = -low;
        for (int k = 0; k < 8; ++k)
            if (out.used >> k & 1) low = std::min(low, lo[k]), high = std::max(high, hi[k]);
        if (!(low <= high)) low = high = 0.0f;  // no slot used (never made: a node has a child)
        const float scale = scale_for(low, high);
        out.origin[a] = low, out.scale[a] = scale;
        for (int k = 0; k < 8; ++k) {
            const bool used = out.used >> k & 1;
            out.q[16 * a + k] = used ? quantise_low(lo[k], scale, low) : 255;
            out.q[16 * a + 8 + k] = used ? quantise_high(hi[k], scale, low) : 0;
        }
    }
    std::memcpy(out.child, node.child, sizeof out.child);
}

}  // namespace bvhlab
