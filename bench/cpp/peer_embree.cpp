// Embree 3 (Debian's libembree-dev) as a benchmark peer: a triangle scene committed at LOW
// (Morton), MEDIUM (binned SAH, the default) or HIGH (spatial splits) quality, rtcIntersect1 per
// ray. Its tree's SAH is measured on a binary tree built by rtcBuildBVH at the same quality
// (leaves of at most 8, C_trav = C_isect = 1), in bvhlab's convention. Shadow rays: rtcOccluded1.
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <embree3/rtcore.h>

#include "bench_data.h"
#include "embree_rays.h"

namespace bench {
namespace {

struct BinaryNode {
    RTCBounds box[2];
    void* child[2];
    unsigned count;  // 0: inner; else a leaf of this many primitives
};

double area(const RTCBounds& b) {
    double x = b.upper_x - b.lower_x, y = b.upper_y - b.lower_y, z = b.upper_z - b.lower_z;
    return x * y + y * z + z * x;
}

/// Σ over the subtree of A(n)·(1 for an inner node, N for a leaf), n = the children of `node`.
double weighted_area(const BinaryNode* node) {
    double sum = 0;
    for (int k = 0; k < 2; ++k) {
        auto* c = static_cast<const BinaryNode*>(node->child[k]);
        sum += area(node->box[k]) * (c->count ? c->count : 1.0) + (c->count ? 0.0 : weighted_area(c));
    }
    return sum;
}

class EmbreePeer : public Peer {
public:
    EmbreePeer(const std::string& quality, unsigned threads) : quality_name_(quality) {
        if (quality == "low") quality_ = RTC_BUILD_QUALITY_LOW;
        else if (quality == "medium" || quality.empty()) quality_ = RTC_BUILD_QUALITY_MEDIUM;
        else if (quality == "high") quality_ = RTC_BUILD_QUALITY_HIGH;
        else throw std::invalid_argument("embree quality must be low, medium or high");
        device_ = rtcNewDevice(("threads=" + std::to_string(threads ? threads : 0)).c_str());
        if (!device_) throw std::runtime_error("rtcNewDevice failed");
    }
    ~EmbreePeer() override {
        if (scene_) rtcReleaseScene(scene_);
        rtcReleaseDevice(device_);
    }
    std::string name() const override { return "Embree 3 " + quality_name_; }

    void build(const Mesh& mesh) override {
        if (vertices_.empty()) copy_mesh(mesh);
        if (scene_) rtcReleaseScene(scene_);
        scene_ = rtcNewScene(device_);
        rtcSetSceneBuildQuality(scene_, quality_);
        RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetGeometryBuildQuality(geom, quality_);
        rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices_.data(), 0,
                                   3 * sizeof(float), mesh.count() * 3);
        rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices_.data(), 0,
                                   3 * sizeof(unsigned), mesh.count());
        rtcCommitGeometry(geom);
        rtcAttachGeometry(scene_, geom);
        rtcReleaseGeometry(geom);
        rtcCommitScene(scene_);
        count_ = mesh.count();
    }

    TreeInfo info() const override {
        if (quality_ == RTC_BUILD_QUALITY_HIGH) return {};  // spatial splits need a split callback
        return binary_tree_info();
    }

    void trace(const Rays& rays, float* t, std::uint32_t* prim) override { embree_trace(scene_, rays, t, prim); }
    void occluded(const Rays& rays, std::uint8_t* out) override { embree_occluded(scene_, rays, out); }

private:
    void copy_mesh(const Mesh& mesh) {
        vertices_.assign(mesh.xyz.begin(), mesh.xyz.end());
        vertices_.push_back(0.0f);  // Embree reads the last vertex with a 16-byte load
        indices_.resize(3 * mesh.count());
        for (unsigned i = 0; i < indices_.size(); ++i) indices_[i] = i;
    }

    TreeInfo binary_tree_info() const {
        std::vector<RTCBuildPrimitive> prims(count_);
        for (unsigned i = 0; i < count_; ++i) {
            const float* v = vertices_.data() + 9 * std::size_t(i);
            RTCBuildPrimitive& p = prims[i];
            p.lower_x = std::fmin(v[0], std::fmin(v[3], v[6])), p.upper_x = std::fmax(v[0], std::fmax(v[3], v[6]));
            p.lower_y = std::fmin(v[1], std::fmin(v[4], v[7])), p.upper_y = std::fmax(v[1], std::fmax(v[4], v[7]));
            p.lower_z = std::fmin(v[2], std::fmin(v[5], v[8])), p.upper_z = std::fmax(v[2], std::fmax(v[5], v[8]));
            p.geomID = 0, p.primID = i;
        }
        RTCBVH bvh = rtcNewBVH(device_);
        RTCBuildArguments args = rtcDefaultBuildArguments();
        args.buildQuality = quality_;
        args.maxBranchingFactor = 2, args.maxLeafSize = 8, args.maxDepth = 64;
        args.bvh = bvh, args.primitives = prims.data(), args.primitiveCount = prims.size();
        args.primitiveArrayCapacity = prims.size();
        args.createNode = [](RTCThreadLocalAllocator a, unsigned, void*) -> void* {
            auto* n = static_cast<BinaryNode*>(rtcThreadLocalAlloc(a, sizeof(BinaryNode), 16));
            n->count = 0;
            return n;
        };
        args.setNodeChildren = [](void* node, void** children, unsigned n, void*) {
            for (unsigned k = 0; k < n; ++k) static_cast<BinaryNode*>(node)->child[k] = children[k];
        };
        args.setNodeBounds = [](void* node, const RTCBounds** bounds, unsigned n, void*) {
            for (unsigned k = 0; k < n; ++k) static_cast<BinaryNode*>(node)->box[k] = *bounds[k];
        };
        args.createLeaf = [](RTCThreadLocalAllocator a, const RTCBuildPrimitive*, size_t n, void* user) -> void* {
            auto* leaf = static_cast<BinaryNode*>(rtcThreadLocalAlloc(a, sizeof(BinaryNode), 16));
            leaf->count = unsigned(n);
            ++*static_cast<std::uint64_t*>(user);
            return leaf;
        };
        std::uint64_t leaves = 0;
        args.userPtr = &leaves;
        auto* root = static_cast<BinaryNode*>(rtcBuildBVH(&args));
        TreeInfo info;
        if (root && !root->count) {
            RTCBounds all = root->box[0];
            all.lower_x = std::fmin(all.lower_x, root->box[1].lower_x),
            all.upper_x = std::fmax(all.upper_x, root->box[1].upper_x);
            all.lower_y = std::fmin(all.lower_y, root->box[1].lower_y),
            all.upper_y = std::fmax(all.upper_y, root->box[1].upper_y);
            all.lower_z = std::fmin(all.lower_z, root->box[1].lower_z),
            all.upper_z = std::fmax(all.upper_z, root->box[1].upper_z);
            info.sah = 1.0 + weighted_area(root) / area(all);
            info.nodes = 2 * leaves - 1;
            info.references = count_;  // no spatial splits in this copy (no room in the primitive array)
        }
        rtcReleaseBVH(bvh);
        return info;
    }

    std::string quality_name_;
    RTCBuildQuality quality_;
    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
    std::vector<float> vertices_;
    std::vector<unsigned> indices_;
    std::size_t count_ = 0;
};

}  // namespace

std::unique_ptr<Peer> make_embree_peer(const std::string& quality, unsigned threads) {
    return std::make_unique<EmbreePeer>(quality, threads);
}

}  // namespace bench
