// ray_order.h — the order in which the wide tree's batch queries trace an incoherent batch: by
// octant, then by the cell of the scene's box that holds the origin (a 16×16×16 grid, or 8×8×8 for
// a smaller block, in Morton order), so that rays traced one after another start near one
// another, go the same way and read the same nodes while the caches still hold them. Ray
// reordering for memory coherence: Pharr, Kolb, Gershbein and Hanrahan 1997; sorting by origin
// cell and direction: Garanzha and Loop 2010 (their hashed keys), Eisenacher et al. 2013 (sorted
// deferred shading). A batch whose rays already come in such an order (a camera's, shadow rays
// cast in pixel order) keeps its own: its sampled neighbours mostly share a key. Used by
// ray_batch.h for_each_block.
#pragma once
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "bvhlab/aabb.h"
#include "bvhlab/big_vector.h"
#include "bvhlab/traverse.h"

namespace bvhlab {

/// Rays of a batch ordered at a time: a block's index array is 4 MiB, at most, whatever the batch.
inline constexpr std::size_t kOrderBlock = std::size_t(1) << 20;
/// Blocks of fewer rays keep their order: the sort's tables would cost more than the caches save.
inline constexpr std::size_t kOrderLeast = 4096;
/// Pairs of neighbouring rays sampled to tell whether a block is coherent already, and how many
/// of them, at most, may differ in key for it to keep its order.
inline constexpr std::uint32_t kOrderSamples = 256, kOrderCoherent = kOrderSamples / 4;
/// The wide nodes a ray visits, on average over a sample of the block (for_each_block's probe),
/// from which the block is reordered. Sorted outside the library, the bench's random rays were
/// traced 9% faster on vast1m (3.6 wide nodes a ray), 14% on room1m (5.3), 18% on Sponza (5.9), 19%
/// on repeat1m (6.7), 28% on rods1m (12.8) and 76% on uniform1m (20.4); the sort, the copy and
/// putting the results back cost ~35 ns a ray on the 2-core AMD EPYC VM of that measurement, which
/// on its room1m and vast1m is more than the gain, on Sponza as much (design.md, "Rays in the order
/// of their origins").
inline constexpr double kOrderNodes = 8.0;
/// And, where they visit fewer, the time a ray of the block waits on memory (ns), over which the
/// block is reordered too, from its kOrderWarmRays-th ray on (for_each_block): after the block's
/// first rays, traced as they are, a sample of the rest is traced twice, the first time with the
/// caches as those rays left them, the second with all its lines cached; the difference a ray.
/// The sort and putting the results back cost ~20-25 ns a ray (a 2-core Intel Xeon VM,
/// 2026-12-06), so the order pays where the rays wait a few times that. Measured there after
/// 2,048 rays, each batch traced between Embree's and tinybvh's passes: Sponza's random and
/// shadow rays waited 126-138 and 175-361 ns a ray and gain 0-2% and 6% from the order,
/// repeat1m's random rays 436-466 ns (+7%), but room1m's 38-73 and 9-31 ns and vast1m's 12-14
/// and 8-9 ns, which lose 14-20% and 30-37% to it (73: a process's first batch, its tree not yet
/// in the caches; design.md, "Rays in the order of their origins"). A timed choice changes the
/// speed only, never a result.
inline constexpr double kOrderStallNs = 80.0;
/// The rays a block traces as it is before its wait on memory is measured, and the fewest a block
/// must have for that (the rest is traced after the timed sample, on the calling thread alone: a
/// block of 4,096 rays on several threads waited on it, 76-79 → 87 ns a ray in the review's run).
inline constexpr std::size_t kOrderWarmRays = 2048, kOrderTimedLeast = 16 * kOrderWarmRays;
/// The wait on memory (ns a ray, as kOrderStallNs) from which a timed block's rest goes through the
/// interleaved closest-hit walk (wide_bvh.h WideWalk::Interleaved: intersect_batch; for_each_block: a
/// block whose rays visit at least kOrderNodes wide nodes goes so whole, untimed; one of fewer than
/// kOrderLeast rays, or in ray order already, never). Interleaving costs where the tree stays in
/// the caches (+30% instructions a ray on Sponza's and room1m's random rays) and gains where it
/// does not. Measured on a 2-core AMD EPYC VM (Zen 5, 2026-12-06), random rays ÷ the faster of
/// Embree 3 MEDIUM and tinybvh 1.9 through the batch, alone → interleaved (every block forced
/// interleaved, one A/B run): waits of 360-385 ns a ray (repeat1m) 1.04-1.07 → 1.88-1.95; 150-160
/// ns (Sponza, whose block is reordered) 1.06 → 0.86-0.97; 60-65 ns (room1m) and 12-15 (vast1m)
/// lose 10-25% (design.md, "Several rays at once on a thread", has the chosen version's run).
inline constexpr double kInterleaveStallNs = 250.0;
namespace detail {
/// The wait (ns a ray) the batch queries reorder over: kOrderStallNs, but -inf or +inf in tests
/// that need the timed choice made one way (test_ray_order.cpp).
inline std::atomic<double> order_stall_ns{kOrderStallNs};
/// The wait over which they interleave: kInterleaveStallNs, or ±inf in tests, as order_stall_ns.
inline std::atomic<double> interleave_stall_ns{kInterleaveStallNs};
}  // namespace detail

/// The key of a ray: its octant (the sign bits of its direction, as the batch walks group them)
/// above the Morton code of its origin's cell in a grid of 2^bits cells an axis over `scene`
/// (an origin outside it, or not a number, in the nearest cell or cell 0: the key only orders).
struct RayKeys {
    RayKeys(const Aabb& scene, std::size_t rays);  ///< 2^4 cells an axis from 16 · kOrderLeast rays, else 2^3
    std::uint32_t operator()(const float* origin, const float* direction) const;
    /// The keys of n rays (3 floats each in origins and directions), the same as operator()'s: eight
    /// at a time where the active instruction set has a vector pass (AVX2: ray_piece_avx2.cpp;
    /// 62 instructions a key one at a time, a tenth of a sorted Sponza batch's work besides the walks).
    void of_rays(const float* origins, const float* directions, std::uint32_t n, std::uint16_t* key) const;
    std::uint32_t count() const { return 8u << (3 * bits); }  ///< keys are below this

    int bits;
    float lo[3], scale[3], top;
};

/// Whether rays [0, block.count) come in an order close to RayKeys' already (a camera's, shadow
/// rays cast in pixel order): at most kOrderCoherent of kOrderSamples pairs of neighbours, spread
/// over the block, differ in key.
bool in_ray_order(const RayBatch& block, const RayKeys& keys);

/// A block's rays (at most kOrderBlock) copied in the order of their keys, ties in input order:
/// position k holds the block's ray index[k], whose origin, direction and (where the block has
/// them) tmax are copied. Made in one pass over the block's arrays in their order, and read in
/// order by the walks, so that neither reads the caller's arrays out of order (a gather from them
/// at every piece cost twice as much where the tree filled the caches: design.md).
/// BigVectors: grown without a pass of stores before the sort writes them (a vector's resize
/// zero-filled them: 1-1.4% of a sorted Sponza batch's time in memset), from the cache of freed
/// blocks, so that the next batch takes no page faults for them either.
struct SortedRays {
    BigVector<float> origins, directions, tmax_of;
    BigVector<std::uint32_t> index;
    BigVector<std::uint16_t> key;  ///< the keys in input order (sort_rays' own)
    /// The copy as a batch, with `block`'s tmin and tmax.
    RayBatch batch(const RayBatch& block) const;
};
void sort_rays(const RayBatch& block, const RayKeys& keys, SortedRays& out);

/// out[index[k]] = sorted[k] for k in [0, n): results traced in ray order back to their rays,
/// one array at a time (its lines stay in the caches while they are written out of order).
template <class T>
void unsort(const T* sorted, const BigVector<std::uint32_t>& index, T* out) {
    for (std::size_t k = 0; k < index.size(); ++k) out[index[k]] = sorted[k];
}

/// `out`'s arrays from ray `base` on.
inline HitBatch offset(const HitBatch& out, std::size_t base) {
    const auto at = [base](auto* p) { return p ? p + base : p; };
    return {at(out.t), at(out.prim), at(out.kind), at(out.u), at(out.v), at(out.nodes_visited)};
}

/// A reordered block's hits in its rays' order (the fields `out` asks for), then put back.
struct SortedHits {
    BigVector<float> t, u, v;
    BigVector<std::int32_t> prim;
    BigVector<std::uint8_t> kind;
    BigVector<std::uint32_t> visited;
    HitBatch make(const HitBatch& out, std::size_t n) {
        t.resize(n), prim.resize(n);
        const auto field = [n](auto& a, const void* asked) {
            a.resize(asked ? n : 0);
            return asked ? a.data() : nullptr;
        };
        return {t.data(),        prim.data(),     field(kind, out.kind),
                field(u, out.u), field(v, out.v), field(visited, out.nodes_visited)};
    }
    void unsort(const BigVector<std::uint32_t>& index, const HitBatch& out) const {
        bvhlab::unsort(t.data(), index, out.t), bvhlab::unsort(prim.data(), index, out.prim);
        if (out.kind) bvhlab::unsort(kind.data(), index, out.kind);
        if (out.u) bvhlab::unsort(u.data(), index, out.u);
        if (out.v) bvhlab::unsort(v.data(), index, out.v);
        if (out.nodes_visited) bvhlab::unsort(visited.data(), index, out.nodes_visited);
    }
};

}  // namespace bvhlab
