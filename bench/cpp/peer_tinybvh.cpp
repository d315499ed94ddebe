// tinybvh (github.com/jbikker/tinybvh, a local copy: never committed) as a benchmark peer. The
// timed build is BVH::Build (in 1.9 its AVX2 8-bin builder where AVX2 is compiled in) or BuildHQ
// (its SBVH: spatial splits), then Optimize (its reinsertion, Bittner et al. 2013) if asked; rays
// go through BVH8_CPU (8-wide, AVX2) or BVH4_CPU, built by the same builder: Intersect for closest
// hits, IsOccluded for shadow rays. Spec options, comma separated: hq, opt (25 iterations, its
// default) or opt=N, bvh4.
// Built only when CMake is given -DBVHLAB_TINYBVH_DIR=<folder holding tiny_bvh.h>.
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "bench_data.h"

namespace bench {
namespace {

double area(const tinybvh::bvhvec3& lo, const tinybvh::bvhvec3& hi) {
    double x = double(hi.x) - lo.x, y = double(hi.y) - lo.y, z = double(hi.z) - lo.z;
    return x * y + y * z + z * x;
}

struct Options {
    bool hq = false, bvh4 = false;
    std::uint32_t optimize = 0;  ///< Optimize iterations (0: none)
};

Options parse_options(const std::string& spec) {
    Options o;
    std::stringstream ss(spec);
    for (std::string kv; std::getline(ss, kv, ',');) {
        if (kv.empty()) continue;
        if (kv == "hq") o.hq = true;
        else if (kv == "bvh4") o.bvh4 = true;
        else if (kv == "opt") o.optimize = 25;
        else if (kv.rfind("opt=", 0) == 0) o.optimize = std::uint32_t(std::stoul(kv.substr(4)));
        else throw std::invalid_argument("unknown tinybvh option '" + kv + "' (hq, opt, opt=N, bvh4)");
    }
    return o;
}

/// Builds `tree` (a BVH, BVH8_CPU or BVH4_CPU) as the options say.
template <class Tree>
void build_with(Tree& tree, const Options& o, const tinybvh::bvhvec4* verts, std::uint32_t count) {
    if (o.hq) tree.BuildHQ(verts, count);
    else tree.Build(verts, count);  // 1.9: picks its AVX2 binned builder
    if (o.optimize) tree.Optimize(o.optimize, false);
}

class TinyBvhPeer : public Peer {
public:
    TinyBvhPeer(const std::string& spec, unsigned threads) : options_(parse_options(spec)), threads_(threads) {}
    std::string name() const override {
        return std::string("tinybvh ") + (options_.hq ? "BuildHQ" : "Build") +
               (options_.optimize ? " + Optimize(" + std::to_string(options_.optimize) + ")" : "") +
               (options_.bvh4 ? " / BVH4_CPU" : " / BVH8_CPU");
    }

    void build(const Mesh& mesh) override {
        if (verts_.empty()) {
            verts_.resize(3 * mesh.count());
            for (std::size_t i = 0; i < verts_.size(); ++i)
                verts_[i] = tinybvh::bvhvec4(mesh.xyz[3 * i], mesh.xyz[3 * i + 1], mesh.xyz[3 * i + 2], 0.0f);
        }
        bvh_.threadedBuild = threads_ != 1;
        build_with(bvh_, options_, verts_.data(), std::uint32_t(mesh.count()));
    }

    /// The binary tree's SAH in bvhlab's convention (bench_data.h TreeInfo), a BuildHQ leaf's
    /// duplicated references counted as primitives.
    TreeInfo info() const override {
        const auto* nodes = bvh_.bvhNode;
        double sum = 0;
        std::uint64_t count = 0, references = 0;
        std::vector<std::uint32_t> stack{0};
        while (!stack.empty()) {
            const auto& n = nodes[stack.back()];
            stack.pop_back();
            ++count, references += n.isLeaf() ? n.triCount : 0;
            sum += area(n.aabbMin, n.aabbMax) * (n.isLeaf() ? double(n.triCount) : 1.0);
            if (!n.isLeaf()) stack.push_back(n.leftFirst), stack.push_back(n.leftFirst + 1);
        }
        return {sum / area(nodes[0].aabbMin, nodes[0].aabbMax), count, references};
    }

    void prepare_trace() override {
        const auto count = std::uint32_t(verts_.size() / 3);
        if (options_.bvh4) {
            bvh4_.bvh4.bvh.threadedBuild = threads_ != 1;
            build_with(bvh4_, options_, verts_.data(), count);
        } else {
            bvh8_.bvh8.bvh.threadedBuild = threads_ != 1;
            build_with(bvh8_, options_, verts_.data(), count);
        }
    }

    void trace(const Rays& rays, float* t, std::uint32_t* prim) override {
        const float inf = std::numeric_limits<float>::infinity();
        for (std::size_t i = 0; i < rays.count(); ++i) {
            const float* r = rays.od.data() + 6 * i;
            tinybvh::Ray ray({r[0], r[1], r[2]}, {r[3], r[4], r[5]});  // normalises the direction
            if (options_.bvh4) bvh4_.Intersect(ray);
            else bvh8_.Intersect(ray);
            const bool miss = ray.hit.t >= BVH_FAR;
            const float scale = std::sqrt(r[3] * r[3] + r[4] * r[4] + r[5] * r[5]);
            t[i] = miss ? inf : ray.hit.t / scale;
            prim[i] = miss ? ~0u : ray.hit.prim;
        }
    }

    void occluded(const Rays& rays, std::uint8_t* out) override {
        for (std::size_t i = 0; i < rays.count(); ++i) {
            const float* r = rays.od.data() + 6 * i;
            const float scale = std::sqrt(r[3] * r[3] + r[4] * r[4] + r[5] * r[5]);
            // the direction is normalised, so the segment's end in its units is tmax · |d|
            const tinybvh::Ray ray({r[0], r[1], r[2]}, {r[3], r[4], r[5]}, rays.tmax[i] * scale);
            out[i] = options_.bvh4 ? bvh4_.IsOccluded(ray) : bvh8_.IsOccluded(ray);
        }
    }

private:
    Options options_;
    unsigned threads_;
    std::vector<tinybvh::bvhvec4> verts_;
    tinybvh::BVH bvh_;
    tinybvh::BVH8_CPU bvh8_;
    tinybvh::BVH4_CPU bvh4_;
};

}  // namespace

std::unique_ptr<Peer> make_tinybvh_peer(const std::string& spec, unsigned threads) {
    return std::make_unique<TinyBvhPeer>(spec, threads);
}

}  // namespace bench
