// ray_order.h — the order in which the wide tree's batch queries trace an incoherent batch: by
// octant, then by the cell of the scene's box that holds the origin (a 16×16×16 grid, or 8×8×8 for
// a smaller block, in Morton order), so that rays traced one after another start near one
// another, go the same way and read the same nodes while the caches still hold them. Ray
// reordering for memory coherence: Pharr, Kolb, Gershbein and Hanrahan 1997; sorting by origin
// cell and direction: Garanzha and Loop 2010 (their hashed keys), Eisenacher et al. 2013 (sorted
// deferred shading). A batch whose rays already come in such an order (a camera's, shadow rays
// cast in pixel order) keeps its own: its sampled neighbours mostly share a key.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "bvhlab/aabb.h"
#include "bvhlab/traverse.h"

namespace bvhlab {

/// Rays of a batch ordered at a time: a block's index array is 4 MiB, at most, whatever the batch.
inline constexpr std::size_t kOrderBlock = std::size_t(1) << 20;
/// Blocks of fewer rays keep their order: the sort's tables would cost more than the caches save.
inline constexpr std::size_t kOrderLeast = 4096;
/// Pairs of neighbouring rays sampled to tell whether a block is coherent already, and how many
/// of them, at most, may differ in key for it to keep its order.
inline constexpr std::uint32_t kOrderSamples = 256, kOrderCoherent = kOrderSamples / 4;
/// The wide nodes a ray of a block's first piece visits, on average, from which the rest of the
/// block is reordered. Reordering costs ~45 ns a ray on the bench's host (the keys and their sort,
/// then reading and writing the caller's arrays out of order) and saved, traced from the sorted
/// rays, 9% (vast1m, 3.6 nodes a random ray), 14% (room1m, 5.3), 18% (Sponza, 5.9), 19%
/// (repeat1m, 6.7), 28% (rods1m, 12.8) and 76% (uniform1m, 20.4): a gain only from about 8.
inline constexpr double kOrderNodes = 8.0;

/// The key of a ray: its octant (the sign bits of its direction, as the batch walks group them)
/// above the Morton code of its origin's cell in a grid of 2^bits cells an axis over `scene`
/// (an origin outside it, or not a number, in the nearest cell or cell 0: the key only orders).
struct RayKeys {
    RayKeys(const Aabb& scene, std::size_t rays);  ///< 2^4 cells an axis from 16 · kOrderLeast rays, else 2^3
    std::uint32_t operator()(const float* origin, const float* direction) const;
    std::uint32_t count() const { return 8u << (3 * bits); }  ///< keys are below this

    int bits;
    float lo[3], scale[3], top;
};

/// Whether rays [0, block.count) come in an order close to RayKeys' already (a camera's, shadow
/// rays cast in pixel order): at most kOrderCoherent of kOrderSamples pairs of neighbours, spread
/// over the block, differ in key.
bool in_ray_order(const RayBatch& block, const RayKeys& keys);

/// The order in which to trace rays [0, block.count) (at most kOrderBlock): their indices sorted
/// by key, ties in input order, into `index`.
void order_rays(const RayBatch& block, const RayKeys& keys, std::vector<std::uint32_t>& index);

}  // namespace bvhlab
