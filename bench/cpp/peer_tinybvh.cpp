// tinybvh (github.com/jbikker/tinybvh, a local copy: never committed) as a benchmark peer:
// BVH::Build (in 1.9 its AVX2 8-bin builder where AVX2 is compiled in), and BVH8_CPU (its
// 8-wide AVX2 traversal) for single rays.
// Built only when CMake is given -DBVHLAB_TINYBVH_DIR=<folder holding tiny_bvh.h>.
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "bench_data.h"

namespace bench {
namespace {

double area(const tinybvh::bvhvec3& lo, const tinybvh::bvhvec3& hi) {
    double x = double(hi.x) - lo.x, y = double(hi.y) - lo.y, z = double(hi.z) - lo.z;
    return x * y + y * z + z * x;
}

class TinyBvhPeer : public Peer {
public:
    explicit TinyBvhPeer(unsigned threads) : threads_(threads) {}
    std::string name() const override { return "tinybvh Build / BVH8_CPU"; }

    void build(const Mesh& mesh) override {
        if (verts_.empty()) {
            verts_.resize(3 * mesh.count());
            for (std::size_t i = 0; i < verts_.size(); ++i)
                verts_[i] = tinybvh::bvhvec4(mesh.xyz[3 * i], mesh.xyz[3 * i + 1], mesh.xyz[3 * i + 2], 0.0f);
        }
        bvh_.threadedBuild = threads_ != 1;
        bvh_.Build(verts_.data(), std::uint32_t(mesh.count()));  // 1.9: picks its AVX2 binned builder
    }

    TreeInfo info() const override {
        const auto* nodes = bvh_.bvhNode;
        double sum = 0;
        std::vector<std::uint32_t> stack{0};
        while (!stack.empty()) {
            const auto& n = nodes[stack.back()];
            stack.pop_back();
            sum += area(n.aabbMin, n.aabbMax) * (n.isLeaf() ? double(n.triCount) : 1.0);
            if (!n.isLeaf()) stack.push_back(n.leftFirst), stack.push_back(n.leftFirst + 1);
        }
        return {sum / area(nodes[0].aabbMin, nodes[0].aabbMax), bvh_.usedNodes - 1};  // node 1 is unused
    }

    void prepare_trace() override {
        bvh8_.bvh8.bvh.threadedBuild = threads_ != 1;
        bvh8_.Build(verts_.data(), std::uint32_t(verts_.size() / 3));
    }

    void trace(const Rays& rays, float* t, std::uint32_t* prim) override {
        const float inf = std::numeric_limits<float>::infinity();
        for (std::size_t i = 0; i < rays.count(); ++i) {
            const float* r = rays.od.data() + 6 * i;
            tinybvh::Ray ray({r[0], r[1], r[2]}, {r[3], r[4], r[5]});  // normalises the direction
            bvh8_.Intersect(ray);
            const bool miss = ray.hit.t >= BVH_FAR;
            const float scale = std::sqrt(r[3] * r[3] + r[4] * r[4] + r[5] * r[5]);
            t[i] = miss ? inf : ray.hit.t / scale;
            prim[i] = miss ? ~0u : ray.hit.prim;
        }
    }

private:
    unsigned threads_;
    std::vector<tinybvh::bvhvec4> verts_;
    tinybvh::BVH bvh_;
    tinybvh::BVH8_CPU bvh8_;
};

}  // namespace

std::unique_ptr<Peer> make_tinybvh_peer(const std::string&, unsigned threads) {
    return std::make_unique<TinyBvhPeer>(threads);
}

}  // namespace bench
