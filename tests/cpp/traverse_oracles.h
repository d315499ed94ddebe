// traverse_oracles.h — what the traversal tests (test_traverse, test_traverse_occluded, test_tlas)
// check against and with: brute force over every primitive, random rays, the instruction set paths.
#pragma once
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/isa.h"
#include "bvhlab/ray.h"
#include "bvhlab/traverse.h"

namespace bvhlab::test {

/// The oracle: every primitive, no tree.
inline Hit brute_force(const Bvh& bvh, const Ray& ray) {
    RayQuery q(ray);
    Hit hit;
    hit.t = ray.tmax;
    for (std::uint32_t k = 0; k < bvh.prims.size(); ++k)
        if (hit_prim(bvh.prims[k], q, hit)) hit.slot = k;
    if (hit.ref == kNoHit) hit.t = kInfinity;
    return hit;
}

/// The same float, bit for bit (a zero's sign and a NaN's payload too).
inline bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// The same hit bit for bit: distance, primitive, barycentrics and leaf slot (what the traversals
/// promise one another: design.md "Conventions").
inline bool same_hit(const Hit& a, const Hit& b) {
    return same_bits(a.t, b.t) && a.ref == b.ref && same_bits(a.u, b.u) && same_bits(a.v, b.v) && a.slot == b.slot;
}

/// Rays through the test scenes' cube (test_scenes.h), some axis-parallel, some unnormalised.
inline std::vector<Ray> random_rays(std::uint32_t n, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-2.0f, 12.0f);
    std::normal_distribution<float> g(0.0f, 1.0f);
    std::vector<Ray> rays;
    for (std::uint32_t i = 0; i < n; ++i) {
        Vec3 d{g(rng), g(rng), g(rng)};
        if (i % 7 == 0) d.y = 0;  // axis-parallel components
        if (i % 11 == 0) d = {0, 0, i % 2 ? 1.0f : -1.0f};
        if (i % 5 == 0) d = d * 3.7f;  // unnormalised
        rays.push_back({{u(rng), u(rng), u(rng)}, d});
    }
    return rays;
}

/// A batch's arrays (N×3 origins and directions, N tmax) made from rays, for the batch queries.
struct RayArrays {
    std::vector<float> o, d, tmax;
    explicit RayArrays(const std::vector<Ray>& rays) {
        for (const Ray& r : rays) {
            o.insert(o.end(), {r.origin.x, r.origin.y, r.origin.z}), d.insert(d.end(), {r.dir.x, r.dir.y, r.dir.z});
            tmax.push_back(r.tmax);
        }
    }
    RayBatch batch() const { return {o.data(), d.data(), tmax.size(), 0.0f, kInfinity, tmax.data()}; }
};

/// The instruction set paths this CPU can run (isa.h).
inline std::vector<Isa> supported_isas() {
    std::vector<Isa> out;
    for (Isa isa : {Isa::Portable, Isa::Avx2, Isa::Avx512})
        if (isa_supported(isa)) out.push_back(isa);
    return out;
}

}  // namespace bvhlab::test
