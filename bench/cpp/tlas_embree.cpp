// Embree 3's two-level scene as a tlas_bench peer: one scene per mesh (MEDIUM), instanced by
// RTC_GEOMETRY_TYPE_INSTANCE geometries (3×4 row-major transforms) into a top scene (MEDIUM),
// rtcIntersect1 / rtcOccluded1 per ray — Embree's own instancing, the peer of bvhlab's TLAS.
#include <limits>
#include <stdexcept>

#include <embree3/rtcore.h>

#include "embree_rays.h"
#include "tlas_bench.h"

namespace bench {
namespace {

class EmbreeTwoLevel : public InstancedPeer {
public:
    EmbreeTwoLevel() : device_(rtcNewDevice("threads=1")) {
        if (!device_) throw std::runtime_error("rtcNewDevice failed");
    }
    ~EmbreeTwoLevel() override {
        release();
        rtcReleaseDevice(device_);
    }
    std::string name() const override { return "Embree 3 two-level MEDIUM"; }

    void build(const InstancedScene& s) override {
        release();
        vertices_.assign(s.meshes.size(), {}), indices_.assign(s.meshes.size(), {});
        for (std::size_t k = 0; k < s.meshes.size(); ++k) meshes_.push_back(mesh_scene(s.meshes[k], k));
        top_ = rtcNewScene(device_);
        for (std::size_t i = 0; i < s.mesh_of.size(); ++i) {
            RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(g, meshes_[s.mesh_of[i]]);
            rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, s.transforms[i].data());
            rtcCommitGeometry(g);
            rtcAttachGeometry(top_, g);
            rtcReleaseGeometry(g);
        }
        rtcCommitScene(top_);
    }

    void trace(const Rays& rays, float* t, std::uint32_t* prim) override { embree_trace(top_, rays, t, prim); }
    void occluded(const Rays& rays, std::uint8_t* out) override { embree_occluded(top_, rays, out); }

private:
    RTCScene mesh_scene(const Mesh& mesh, std::size_t k) {
        vertices_[k].assign(mesh.xyz.begin(), mesh.xyz.end());
        vertices_[k].push_back(0.0f);  // Embree reads the last vertex with a 16-byte load
        indices_[k].resize(3 * mesh.count());
        for (unsigned i = 0; i < indices_[k].size(); ++i) indices_[k][i] = i;
        RTCScene scene = rtcNewScene(device_);
        RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices_[k].data(), 0,
                                   3 * sizeof(float), mesh.count() * 3);
        rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices_[k].data(), 0,
                                   3 * sizeof(unsigned), mesh.count());
        rtcCommitGeometry(geom);
        rtcAttachGeometry(scene, geom);
        rtcReleaseGeometry(geom);
        rtcCommitScene(scene);
        return scene;
    }

    void release() {
        if (top_) rtcReleaseScene(top_);
        for (RTCScene m : meshes_) rtcReleaseScene(m);
        top_ = nullptr, meshes_.clear();
    }

    RTCDevice device_;
    RTCScene top_ = nullptr;
    std::vector<RTCScene> meshes_;
    std::vector<std::vector<float>> vertices_;
    std::vector<std::vector<unsigned>> indices_;
};

}  // namespace

std::unique_ptr<InstancedPeer> make_embree_two_level() { return std::make_unique<EmbreeTwoLevel>(); }

}  // namespace bench
