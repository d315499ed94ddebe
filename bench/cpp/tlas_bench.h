// tlas_bench.h — what tlas_bench (instanced scenes, issue 34) times: a scene of meshes and their
// instances, and the systems that trace it (a two-level tree, or one flat tree over its triangles
// moved into the world).
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bench_data.h"

namespace bench {

/// Meshes and instances: instance i places meshes[mesh_of[i]] by transforms[i] (3×4 row-major
/// object-to-world, Embree's RTC_FORMAT_FLOAT3X4_ROW_MAJOR).
struct InstancedScene {
    std::vector<Mesh> meshes;
    std::vector<std::uint32_t> mesh_of;
    std::vector<std::array<float, 12>> transforms;
    /// Every instance's triangles moved into the world, in instance order (float arithmetic).
    Mesh flattened() const;
};

/// One system under test on an instanced scene (Peer's trace and occluded, one ray at a time or
/// as a batch).
class InstancedPeer {
public:
    virtual ~InstancedPeer() = default;
    virtual std::string name() const = 0;
    virtual void build(const InstancedScene& scene) = 0;
    /// Before a ray set's timed passes (Peer::prepare_rays: a batch's split copy).
    virtual void prepare_rays(const Rays&) {}
    virtual void trace(const Rays& rays, float* t, std::uint32_t* prim) = 0;
    virtual void occluded(const Rays& rays, std::uint8_t* occluded) = 0;
};

/// Embree 3's two-level scene ("two/embree", tlas_embree.cpp; missing_embree.cpp without Embree).
std::unique_ptr<InstancedPeer> make_embree_two_level();

}  // namespace bench
