#include "ray_order.h"

#include "wide_kernel.h"

namespace bvhlab {
namespace {

/// The bits of a cell coordinate below 16 spread three apart (bit b to bit 3b): Morton order.
constexpr std::uint32_t kSpread[16] = {0x000, 0x001, 0x008, 0x009, 0x040, 0x041, 0x048, 0x049,
                                       0x200, 0x201, 0x208, 0x209, 0x240, 0x241, 0x248, 0x249};

}  // namespace

RayKeys::RayKeys(const Aabb& scene, std::size_t rays)
    : bits(rays >= 16 * kOrderLeast ? 4 : 3), top(float((1 << bits) - 1)) {
    const float cells = float(1 << bits);
    for (int a = 0; a < 3; ++a) {
        const float extent = scene.hi[a] - scene.lo[a];
        lo[a] = scene.lo[a];
        // a flat, empty or unbounded box: every origin in cell 0 on that axis
        scale[a] = extent > 0.0f && extent < kInfinity ? cells / extent : 0.0f;
        if (!(scale[a] < kInfinity)) scale[a] = 0.0f;  // an extent so small that cells / extent overflows
    }
}

std::uint32_t RayKeys::operator()(const float* origin, const float* direction) const {
    std::uint32_t key = 0;
    for (int a = 0; a < 3; ++a) {
        const float x = (origin[a] - lo[a]) * scale[a];
        // NaN (a NaN origin, or inf · 0) to cell 0: the first comparison is false for it
        const std::uint32_t cell = x > 0.0f ? (x < top ? std::uint32_t(x) : std::uint32_t(top)) : 0u;
        key |= kSpread[cell] << a;
    }
    return octant_of(direction) << (3 * bits) | key;
}

bool in_ray_order(const RayBatch& block, const RayKeys& keys) {
    const auto key_of = [&](std::size_t i) { return keys(block.origins + 3 * i, block.directions + 3 * i); };
    if (block.count < 2) return true;
    std::uint32_t differ = 0;
    for (std::uint32_t s = 0; s < kOrderSamples; ++s) {
        const std::size_t i = std::size_t(std::uint64_t(s) * (block.count - 1) / kOrderSamples);
        differ += key_of(i) != key_of(i + 1);
    }
    return differ <= kOrderCoherent;
}

RayBatch SortedRays::batch(const RayBatch& block) const {
    RayBatch b = block;
    b.origins = origins.data(), b.directions = directions.data();
    b.tmax_of = block.tmax_of ? tmax_of.data() : nullptr;
    return b;
}

void sort_rays(const RayBatch& block, const RayKeys& keys, SortedRays& out) {
    const auto n = std::uint32_t(block.count);
    // a stable counting sort of the keys (16 bits: below 8 · 2^12)
    out.key.resize(n);
    std::uint16_t* key = out.key.data();
    keys.of_rays(block.origins, block.directions, n, key);
    std::vector<std::uint32_t> start(keys.count() + 1, 0);
    for (std::uint32_t i = 0; i < n; ++i) ++start[1 + key[i]];
    for (std::uint32_t k = 0; k < keys.count(); ++k) start[k + 1] += start[k];
    out.origins.resize(3 * std::size_t(n)), out.directions.resize(3 * std::size_t(n)), out.index.resize(n);
    out.tmax_of.resize(block.tmax_of ? n : 0);
    float *origins = out.origins.data(), *directions = out.directions.data(), *tmax_of = out.tmax_of.data();
    std::uint32_t* index = out.index.data();
    for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint32_t k = start[key[i]]++;
        std::memcpy(origins + 3 * std::size_t(k), block.origins + 3 * std::size_t(i), 3 * sizeof(float));
        std::memcpy(directions + 3 * std::size_t(k), block.directions + 3 * std::size_t(i), 3 * sizeof(float));
        if (block.tmax_of) tmax_of[k] = block.tmax_of[i];
        index[k] = i;
    }
}

}  // namespace bvhlab
